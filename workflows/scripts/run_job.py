#!/usr/bin/python3
"""One job of the evaluation workflow: runs a crowdslam command into a staging directory and renames it
to its final place only when the command succeeded, so an interrupted or failed job leaves no result.

  run_job.py --out FINAL --kind run|detect [--stdout NAME] -- COMMAND...

`{out}` in COMMAND is replaced by the staging output directory (FINAL.tmp-PID/out, created empty).
The command runs under /usr/bin/time, which gives what run.json does not hold: CPU time (user + system)
and peak RSS of the process, written to time.json. job.json records the command, the machine (host, CPU
model, cores usable, load average before and after) and the start and end. A `run` job counts only when
crowdslam exits 0 and run.json says "completed"; a `detect` job when it exits 0.

Staging directories of killed jobs (FINAL.tmp-PID of a process that no longer runs) are removed before
the job starts. SIGINT, SIGTERM and SIGHUP stop the command and remove the staging directory.
"""
import argparse
import datetime
import json
import os
import platform
import shutil
import signal
import socket
import subprocess
import sys
import time

TIME_FORMAT = "%e %U %S %M"  # wall s, user s, system s, peak RSS kB


def machine():
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
        with open("/proc/meminfo") as f:
            mem_gb = round(int(f.readline().split()[1]) / 1024 / 1024)
    except OSError:
        mem_gb = None
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    info = {"host": socket.gethostname(), "cpu": cpu, "cores": os.cpu_count(), "cores_usable": usable,
            "mem_gb": mem_gb, "kernel": platform.release()}
    for key in ("SLURM_JOB_ID", "SLURM_JOB_NODELIST", "SLURM_CPUS_PER_TASK"):
        if key in os.environ:
            info[key.lower()] = os.environ[key]
    return info


def loadavg():
    try:
        with open("/proc/loadavg") as f:
            return [float(x) for x in f.read().split()[:3]]
    except OSError:
        return None


def running(pid):
    """True while process `pid` runs. A zombie (killed, not yet reaped: a killed job's orphan waits for
    an init that may be slow to reap it) does not run."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return True  # no /proc: trust kill()


def remove_stale(final):
    parent, base = os.path.split(os.path.abspath(final))
    if not os.path.isdir(parent):
        return
    for name in os.listdir(parent):
        if not name.startswith(base + ".tmp-"):
            continue
        try:
            pid = int(name.rsplit("-", 1)[1])
        except ValueError:
            pid = None
        if pid is not None and running(pid):
            continue
        shutil.rmtree(os.path.join(parent, name), ignore_errors=True)


def parse_time(path):
    # GNU time writes "Command exited with non-zero status N" or "Command terminated by signal N" first.
    with open(path) as f:
        last = [line for line in f.read().splitlines() if line.strip()][-1].split()
    wall, user, system, rss_kb = float(last[0]), float(last[1]), float(last[2]), int(last[3])
    return {"wall_s": wall, "user_s": user, "system_s": system, "cpu_s": user + system, "peak_rss_kb": rss_kb}


def fsync_dir(path):
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True, help="final output directory")
    p.add_argument("--kind", choices=("run", "detect"), required=True)
    p.add_argument("--stdout", help="keep the command's stdout in OUT/NAME")
    p.add_argument("command", nargs=argparse.REMAINDER)
    a = p.parse_args()
    command = a.command[1:] if a.command[:1] == ["--"] else a.command
    if not command:
        p.error("no command")
    final = a.out.rstrip("/")
    remove_stale(final)
    if os.path.exists(final):
        shutil.rmtree(final)
    staging = f"{final}.tmp-{os.getpid()}"
    out = os.path.join(staging, "out")
    os.makedirs(out)
    child = None

    def stop(signum, _frame):
        if child is not None and child.poll() is None:
            child.send_signal(signal.SIGTERM)
            try:
                child.wait(timeout=10)
            except subprocess.TimeoutExpired:
                child.kill()
        shutil.rmtree(staging, ignore_errors=True)
        os._exit(128 + signum)

    for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, stop)
    argv = [c.replace("{out}", out) for c in command]
    timing = os.path.join(staging, "time.txt")
    started, load_before = datetime.datetime.now(datetime.timezone.utc), loadavg()
    t0 = time.monotonic()
    with open(os.path.join(staging, "stdout"), "wb") as stdout:
        child = subprocess.Popen(["/usr/bin/time", "-f", TIME_FORMAT, "-o", timing] + argv, stdout=stdout)
        code = child.wait()
    elapsed = time.monotonic() - t0
    ok = code == 0
    reason = f"exit status {code}"
    if ok and a.kind == "run":
        try:
            with open(os.path.join(out, "run.json")) as f:
                end_state = json.load(f).get("end_state")
        except (OSError, ValueError) as e:
            end_state = f"unreadable run.json ({e})"
        ok, reason = end_state == "completed", f"end_state {end_state}"
    if not ok:
        shutil.rmtree(staging, ignore_errors=True)
        sys.exit(f"run_job: {' '.join(argv)}: {reason}; no result kept for {final}")
    with open(os.path.join(out, "time.json"), "w") as f:
        json.dump(parse_time(timing), f, indent=1)
    if a.stdout:
        os.replace(os.path.join(staging, "stdout"), os.path.join(out, a.stdout))
    job = {"command": argv, "kind": a.kind, "machine": machine(), "load_before": load_before,
           "load_after": loadavg(), "started": started.isoformat(timespec="seconds"),
           "finished": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "elapsed_s": round(elapsed, 3)}
    # job.json is written last: a result directory without it is not a result.
    with open(os.path.join(out, "job.json"), "w") as f:
        json.dump(job, f, indent=1)
        f.flush()
        os.fsync(f.fileno())
    fsync_dir(out)
    os.rename(out, final)
    fsync_dir(os.path.dirname(os.path.abspath(final)))
    shutil.rmtree(staging, ignore_errors=True)


if __name__ == "__main__":
    main()
