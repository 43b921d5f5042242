#!/usr/bin/python3
"""CPU time of a process tree, by process type and thread name (scripts/measure_viewer.sh).

    process_cpu.py ROOT_PID OUT_JSON [--since-start] [--interval S]

With --since-start, the CPU time the tree had used when sampling began is left out (a browser started
earlier counts only from then on). Samples /proc every S seconds (default 0.2) until ROOT_PID exits or
SIGTERM arrives, and once more then, keeping the newest CPU time of every thread of ROOT_PID and its
descendants (threads and processes that ended keep their last sample). Sampling costs CPU on the
machine being measured: a tree that lives through the measurement (a browser started earlier) needs
only the first and the last sample, so use a long interval for it. Then
writes {"total_s": ..., "by_type": {...}, "by_thread": {"type/thread name": seconds}} to OUT_JSON.
The type is Chromium's --type=... (renderer, gpu-process, utility; "browser" without one).
"""
import json
import os
import signal
import sys
import time

TICK = os.sysconf("SC_CLK_TCK")


def read(path):
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError:
        return b""


def stat_fields(raw):
    # comm is in parentheses and may contain spaces: split after the last ')'.
    close = raw.rfind(b")")
    return raw[raw.find(b"(") + 1:close].decode(errors="replace"), raw[close + 2:].split()


def process_type(pid):
    # Chromium rewrites its command line as one space-separated string (setproctitle).
    for arg in read(f"/proc/{pid}/cmdline").replace(b"\0", b" ").split():
        if arg.startswith(b"--type="):
            return arg[7:].decode()
    return "browser"


def descendants(root):
    children = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            _, fields = stat_fields(read(f"/proc/{name}/stat"))
            if len(fields) > 2:
                children.setdefault(int(fields[1]), []).append(int(name))
    out, todo = [], [root]
    while todo:
        pid = todo.pop()
        out.append(pid)
        todo.extend(children.get(pid, []))
    return out


def main():
    root, out_path = int(sys.argv[1]), sys.argv[2]
    since_start = "--since-start" in sys.argv[3:]
    base = {}  # (pid, tid) -> seconds at the first sample (--since-start)
    first = True
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    seen = {}  # (pid, tid) -> (type, thread name, seconds)
    interval = float(sys.argv[sys.argv.index("--interval") + 1]) if "--interval" in sys.argv else 0.2

    def sample():
        nonlocal first
        for pid in descendants(root):
            kind = process_type(pid)  # read again: a process forked by the zygote sets its --type later
            try:
                tids = os.listdir(f"/proc/{pid}/task")
            except OSError:
                continue
            for tid in tids:
                comm, fields = stat_fields(read(f"/proc/{pid}/task/{tid}/stat"))
                if len(fields) > 13:
                    seconds = (int(fields[11]) + int(fields[12])) / TICK
                    if first and since_start:
                        base[(pid, tid)] = seconds
                    seen[(pid, tid)] = (kind, comm, seconds - base.get((pid, tid), 0.0))
        first = False

    while not stop and os.path.exists(f"/proc/{root}"):
        sample()
        deadline = time.monotonic() + interval
        while not stop and time.monotonic() < deadline and os.path.exists(f"/proc/{root}"):
            time.sleep(min(0.1, interval))
    if os.path.exists(f"/proc/{root}"):
        sample()  # the last figures, taken when told to stop
    by_type, by_thread = {}, {}
    for kind, comm, seconds in seen.values():
        by_type[kind] = by_type.get(kind, 0) + seconds
        key = kind + "/" + comm
        by_thread[key] = by_thread.get(key, 0) + seconds
    top = dict(sorted(by_thread.items(), key=lambda kv: -kv[1])[:12])
    with open(out_path, "w") as f:
        json.dump({"total_s": sum(by_type.values()), "by_type": by_type, "by_thread": top}, f, indent=1)


if __name__ == "__main__":
    main()
