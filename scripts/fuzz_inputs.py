#!/usr/bin/env python3
"""Hostile-input fuzzing of the crowdslam command-line tool (issue 37), bounded in time.

Generates cases against saved maps (SQL edits of a real map, damaged bytes), settings files, MOT
detections files, special files (devices, FIFOs, directories), numeric options, and the live viewer's
HTTP server (garbage requests, bad bodies, many event streams, slowloris sockets, with /state probed
after each), runs the built `crowdslam` on each, and reports:
  crash      the process died of a signal it did not ask for (SIGSEGV, SIGABRT, ...)
  hang       no exit within the case's timeout (or a /state probe of the viewer unanswered)
  exit code  anything but 0, 1 or 128+n (2 = an internal error)
  contract   --json not exactly one JSON document, an error that is not one line naming something
  leftover   a temporary ("*.tmp.*", "*.tmp-*") left behind, or an output written by a command that failed
             before its work (a map, an export, a run directory without a final run.json)
Exit status 0 when every case is clean, 1 otherwise (each finding printed with its command).

  scripts/fuzz_inputs.py [--bin build/apps/crowdslam/crowdslam] [--cases 300] [--time-budget 600]
                         [--seed 1] [--only maps,settings,detections,special,options,viewer] [--keep DIR]
The test suite runs a short version (tests/cli: --cases 40 --time-budget 45).
"""
import argparse
import json
import os
import random
import shutil
import socket
import sqlite3
import stat
import subprocess
import sys
import tempfile
import threading
import time

KINDS = ["maps", "settings", "detections", "special", "options", "viewer"]
HOSTILE_NUMBERS = ["9e999", "-9e999", "'abc'", "''", "-1", "0", "4611686018427387904", "-4611686018427387904",
                   "1e308", "x''", "x'00ff'", "0.5", "2147483648", "'1e3'", "' 7'"]
HOSTILE_TEXT = ["abc", "-1", "0", "1e999", "nan", "inf", "", " ", "18446744073709551616", "1e3", "0x10", "\u00e9\u00e9",
                "9" * 40, "1,2", "[1, 2]", "-0", "1e-320"]


class Finding(Exception):
    pass


class Fuzzer:
    def __init__(self, binary, work, seed, timeout):
        self.binary = binary
        self.work = work
        self.rng = random.Random(seed)
        self.timeout = timeout
        self.findings = []
        self.cases = 0
        self.counts = {}

    # --- running and judging one command ---------------------------------------------------------
    def run(self, kind, args, timeout=None, must_not_exist_on_error=(), run_dir=None):
        self.cases += 1
        self.counts[kind] = self.counts.get(kind, 0) + 1
        command = [self.binary, "--json"] + [str(a) for a in args]
        shown = " ".join(command)
        try:
            r = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout or self.timeout,
                               cwd=self.work, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            self.report("hang", shown, f"no exit within {timeout or self.timeout} s")
            return None
        code = r.returncode
        out = r.stdout.decode("utf-8", "replace")
        err = r.stderr.decode("utf-8", "replace")
        if code < 0:
            self.report("crash", shown, f"killed by signal {-code}; stderr tail: {err[-300:]}")
            return r
        if code not in (0, 1) and not 129 <= code <= 128 + 64:
            self.report("exit code", shown, f"exit {code}; stderr tail: {err[-300:]}")
        try:
            json.loads(out)
        except ValueError:
            self.report("contract", shown, f"--json stdout is not one JSON document: {out[:200]!r}")
        if code == 1:
            errors = [line for line in err.splitlines() if line.startswith("error: ")]
            if len(errors) != 1 or len(errors[0]) < 12:
                self.report("contract", shown, f"not one clear error line: {err[-300:]!r}")
            for path in must_not_exist_on_error:
                if os.path.lexists(path):
                    self.report("leftover", shown, f"failed (exit 1) but wrote {path}")
        if run_dir and os.path.isdir(run_dir):
            self.check_run_dir(shown, run_dir)
        self.check_temporaries(shown)
        return r

    def check_run_dir(self, shown, run_dir):
        doc_path = os.path.join(run_dir, "run.json")
        try:
            with open(doc_path) as f:
                state = json.load(f).get("end_state", "")
        except (OSError, ValueError) as e:
            self.report("leftover", shown, f"{run_dir} exists without a readable run.json ({e})")
            return
        if state == "running":
            self.report("leftover", shown, f"{doc_path} still says running after the process ended")

    def check_temporaries(self, shown):
        for root, dirs, files in os.walk(self.work):
            for name in files + dirs:
                if ".tmp." in name or ".tmp-" in name:
                    path = os.path.join(root, name)
                    self.report("leftover", shown, f"temporary left behind: {path}")
                    shutil.rmtree(path, ignore_errors=True) if os.path.isdir(path) else os.remove(path)

    def report(self, what, command, detail):
        self.findings.append((what, command, detail))
        print(f"FINDING [{what}] {command}\n    {detail}", flush=True)

    def fresh(self, name):
        path = os.path.join(self.work, name)
        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path)
        elif os.path.lexists(path):
            os.remove(path)
        return path

    # --- fixtures -----------------------------------------------------------------------------------
    def prepare(self):
        self.dataset = os.path.join(self.work, "seq")
        subprocess.run([self.binary, "-q", "synth", "--out", self.dataset, "--frames", "30", "--width", "320",
                        "--height", "240", "--people", "2"], check=True, cwd=self.work)
        self.base_map = os.path.join(self.work, "base.db")
        subprocess.run([self.binary, "-q", "run", "--dataset", self.dataset, "--out", os.path.join(self.work, "base_run"),
                        "--no-people-filter", "--save-map", self.base_map], check=True, cwd=self.work,
                       stdout=subprocess.DEVNULL)
        with sqlite3.connect(self.base_map) as db:
            self.schema = {t: [c[1] for c in db.execute(f"PRAGMA table_info({t})")]
                           for (t,) in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
            self.metadata_keys = [k for (k,) in db.execute("SELECT key FROM metadata")]
        with open(os.path.join(self.dataset, "settings.yaml")) as f:
            self.settings_lines = f.read().splitlines()
        self.fifo = os.path.join(self.work, "fifo")
        os.mkfifo(self.fifo)
        # Devices to write to are our own nodes (as root), never the real /dev ones: a binary that still
        # replaces a device (an older crowdslam) must not take the machine's /dev/null with it.
        self.write_targets = [self.fifo, self.work]
        for name, minor in (("null", 3), ("full", 7)):
            path = os.path.join(self.work, name)
            try:
                os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
                self.write_targets.append(path)
            except OSError:
                pass

    # --- generators -----------------------------------------------------------------------------------
    def hostile_map(self, path):
        shutil.copy(self.base_map, path)
        rng = self.rng
        if rng.random() < 0.2:  # damaged bytes
            with open(path, "r+b") as f:
                size = os.path.getsize(path)
                choice = rng.random()
                if choice < 0.4:
                    f.truncate(rng.randrange(0, size))
                else:
                    f.seek(rng.randrange(0, size))
                    f.write(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 8192))))
            return "damaged bytes"
        with sqlite3.connect(path) as db:
            choice = rng.random()
            if choice < 0.25:
                key = rng.choice(self.metadata_keys)
                value = rng.choice(HOSTILE_TEXT)
                db.execute("UPDATE metadata SET value = ? WHERE key = ?", (value, key))
                return f"metadata {key} = {value!r}"
            if choice < 0.3:
                table = rng.choice([t for t in self.schema if t != "schema_version"])
                db.execute(f"DROP TABLE {table}")
                return f"drop {table}"
            if choice < 0.35:
                db.execute("UPDATE schema_version SET version = ?", (rng.choice([0, -1, 2, 99, "x"]),))
                return "schema version"
            table = rng.choice(["keyframes", "map_points", "observations", "covisibility", "loop_edges"])
            column = rng.choice(self.schema[table])
            value = rng.choice(HOSTILE_NUMBERS)
            where = rng.choice(["rowid = 1", "rowid = (SELECT MAX(rowid) FROM " + table + ")", "1"])
            try:
                db.execute(f"UPDATE OR IGNORE {table} SET {column} = {value} WHERE {where}")
            except sqlite3.Error as e:
                return f"{table}.{column} = {value} (refused by SQLite: {e})"
            return f"{table}.{column} = {value} where {where}"

    def case_maps(self, i):
        m = self.fresh(f"m{i}.db")
        self.hostile_map(m)
        op = self.rng.choice(["info", "export", "optimise", "load", "load"])
        if op == "info":
            self.run("maps", ["map", "info", m])
        elif op == "export":
            ply, kf, traj = (self.fresh(f"m{i}.{e}") for e in ("ply", "kf.ply", "tum"))
            self.run("maps", ["map", "export", m, "--ply", ply, "--keyframes", kf, "--trajectory", traj],
                     must_not_exist_on_error=[ply, kf, traj])
        elif op == "optimise":
            out = self.fresh(f"m{i}_opt.db")
            self.run("maps", ["map", "optimise", m, "--out", out, "--iterations", "3"], must_not_exist_on_error=[out])
        else:
            out = self.fresh(f"r{i}")
            args = ["run", "--dataset", self.dataset, "--out", out, "--no-people-filter", "--frames", "4",
                    "--load-map", m]
            if self.rng.random() < 0.5:
                args.append("--localization")
            else:
                args += ["--save-map", m, "--overwrite"]
            self.run("maps", args, must_not_exist_on_error=[], run_dir=out)

    def case_settings(self, i):
        path = self.fresh(f"s{i}.yaml")
        lines = list(self.settings_lines)
        rng = self.rng
        choice = rng.random()
        if choice < 0.6:
            keyed = [n for n, line in enumerate(lines) if ":" in line and not line.startswith(("%", "#", " "))]
            n = rng.choice(keyed)
            key = lines[n].split(":")[0]
            value = rng.choice(HOSTILE_TEXT + ['"bogus"', "[]", "{}", "!!opencv-matrix", "0", "1", "-1e9"])
            lines[n] = f"{key}: {value}"
        elif choice < 0.75:
            lines.append(rng.choice(["Detector.tracker", "PeopleFilter.mode", "ORBextractor.nLevels", "Camera.fps",
                                     "Camera.width", "Ground.enabled", "Unknown.key"]) + ": " + rng.choice(HOSTILE_TEXT))
        elif choice < 0.85:
            lines = lines[: rng.randrange(0, len(lines))]
        else:
            data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 4096)))
            with open(path, "wb") as f:
                f.write(data)
            lines = None
        if lines is not None:
            with open(path, "w") as f:
                f.write("\n".join(lines) + "\n")
        out = self.fresh(f"r{i}")
        self.run("settings", ["run", "--dataset", self.dataset, "--settings", path, "--out", out, "--no-people-filter",
                              "--frames", "3", "--allow-untracked"], must_not_exist_on_error=[out], run_dir=out)

    def case_detections(self, i):
        path = self.fresh(f"d{i}.txt")
        rng = self.rng
        rows = []
        for _ in range(rng.randrange(1, 60)):
            fields = [str(rng.randrange(1, 5)), "-1", str(rng.uniform(-50, 400)), str(rng.uniform(-50, 300)),
                      str(rng.uniform(-5, 100)), str(rng.uniform(-5, 200)), str(rng.random())]
            if rng.random() < 0.3:
                fields[rng.randrange(len(fields))] = rng.choice(HOSTILE_TEXT + ["nan", "-inf", "1e40"])
            if rng.random() < 0.1:
                fields = fields[: rng.randrange(len(fields))]
            rows.append(",".join(fields))
        if rng.random() < 0.1:
            rows += ["1,-1,10,10,20,40,0.9"] * 2500  # too many boxes in one frame
        if rng.random() < 0.1:
            rows.append("x" * (9 << 20))  # a line longer than any text line (8 MiB)
        with open(path, "w") as f:
            f.write("\n".join(rows) + "\n")
        out = self.fresh(f"r{i}")
        self.run("detections", ["run", "--dataset", self.dataset, "--detections", path, "--out", out, "--frames", "3",
                                "--allow-untracked"], must_not_exist_on_error=[out], run_dir=out)

    def case_special(self, i):
        out = self.fresh(f"r{i}")
        gt = os.path.join(self.dataset, "groundtruth.txt")
        # Written to: only our own special files (prepare()).
        target = self.rng.choice(self.write_targets)
        writes = [
            ["run", "--dataset", self.dataset, "--out", out, "--save-map", target, "--overwrite", "--frames", "2"],
            ["map", "optimise", self.base_map, "--out", target, "--overwrite"],
            ["map", "export", self.base_map, "--ply", target],
            ["eval", "ate", gt, gt, "--save-aligned", target],
        ]
        if self.rng.random() < 0.35:
            args = self.rng.choice(writes)
            before = os.stat(target, follow_symlinks=False)
            self.run("special", args, timeout=20, run_dir=out if args[0] == "run" else None)
            after = os.stat(target, follow_symlinks=False)
            if stat.S_IFMT(before.st_mode) != stat.S_IFMT(after.st_mode):
                self.report("leftover", " ".join(args), f"{target} was replaced")
            return
        # Only read: the real /dev/zero too.
        target = self.rng.choice(["/dev/zero"] + self.write_targets)
        cases = [
            ["run", "--dataset", self.dataset, "--out", out, "--settings", target],
            ["run", "--dataset", self.dataset, "--out", out, "--detections", target],
            ["run", "--dataset", self.dataset, "--out", out, "--vocabulary", target],
            ["run", "--dataset", self.dataset, "--out", out, "--load-map", target],
            ["run", "--dataset", target, "--out", out],
            ["eval", "ate", target, gt], ["eval", "rpe", gt, target], ["vocab", "info", target],
            ["map", "info", target],
        ]
        args = self.rng.choice(cases)
        self.run("special", args, timeout=20, run_dir=out if args[0] == "run" else None)

    def case_options(self, i):
        out = self.fresh(f"r{i}")
        option = self.rng.choice(["--frames", "--save-frames", "--viewer-port", "--detector-interval",
                                  "--viewer-pause-timeout", "--pace", "--sensor", "--filter-mode", "--out",
                                  "--save-map", "--no-such-option"])
        value = self.rng.choice(HOSTILE_TEXT + ["70000", "-2", "1e99", "sensor"])
        args = ["run", "--dataset", self.dataset, "--out", out, "--no-people-filter", "--frames", "3", option, value,
                "--allow-untracked"]
        if option == "--out":  # the hostile value is the output directory
            args = args[:3] + args[5:]
            out = os.path.join(self.work, value) if value.strip() else None
        self.run("options", args, run_dir=out if out and os.path.isdir(out) and out != self.work else None)

    # --- the viewer -----------------------------------------------------------------------------------
    def viewer_requests(self, port, count, deadline, process):
        """Hostile requests to a live viewer (paused meanwhile, a page connected); after each, /state must
        answer with valid JSON within 2 s."""
        rng = self.rng
        guard = socket.create_connection(("127.0.0.1", port), timeout=2)  # a page: the pause never times out
        guard.sendall(b"GET /events?image=0 HTTP/1.1\r\n\r\n")
        self.post(port, b"/control/pause")
        held = []  # open event streams and slowloris sockets, kept open
        for _ in range(40):  # many viewers at once (beyond the cap of streams: 503)
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.sendall(b"GET /events HTTP/1.1\r\n\r\n")
            held.append(s)
        for _ in range(10):  # slowloris
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.sendall(b"GET /state HTTP/1.1\r\nX-a: 1\r\n")
            held.append(s)
        self.probe_state(port, "40 event streams and 10 slowloris sockets")
        for n in range(count):
            if time.monotonic() > deadline or process.poll() is not None:
                break
            self.cases += 1
            self.counts["viewer"] = self.counts.get("viewer", 0) + 1
            choice = rng.random()
            try:
                s = socket.create_connection(("127.0.0.1", port), timeout=2)
                if choice < 0.2:
                    s.sendall(b"GET /events?image=0 HTTP/1.1\r\n\r\n")
                    held.append(s)
                elif choice < 0.35:
                    s.sendall(b"GET /state HTTP/1.1\r\nX-Slow: ")  # never finished
                    held.append(s)
                elif choice < 0.55:
                    body = rng.choice([b'{"x":1},"run":{"finished":true},"zz":{}', b"not json", b"[1]",
                                       b'{"a":"\xff\xfe"}', b"{" * 5000, b'{"updates":3}', b""])
                    s.sendall(b"POST /client HTTP/1.1\r\nContent-Length: %d\r\n\r\n" % len(body) + body)
                    s.recv(4096)
                    s.close()
                elif choice < 0.7:
                    s.sendall(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 3000))) + b"\r\n\r\n")
                    s.close()
                elif choice < 0.8:
                    s.sendall(b"GET /" + b"a" * rng.randrange(10, 40000) + b" HTTP/1.1\r\n\r\n")
                    s.close()
                elif choice < 0.9:
                    s.sendall(b"POST /client HTTP/1.1\r\nContent-Length: 99999999999\r\n\r\n{}")
                    s.close()
                else:
                    path = rng.choice([b"/control/pause", b"/control/step", b"/../etc/passwd",
                                       b"/events?batch_ms=99999&image_width=-1", b"/state?x=%zz"])
                    s.sendall(b"POST " + path + b" HTTP/1.1\r\nContent-Length: 0\r\n\r\n")
                    s.settimeout(2)
                    s.recv(4096)
                    s.close()
            except OSError:
                pass
            self.probe_state(port, f"viewer request {n}")
            if len(held) > 40:
                for s in held[:20]:
                    s.close()
                del held[:20]
        for s in held:
            s.close()
        self.post(port, b"/control/resume")
        guard.close()

    def post(self, port, path):
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.sendall(b"POST " + path + b" HTTP/1.1\r\nContent-Length: 0\r\n\r\n")
            s.recv(4096)
            s.close()
        except OSError as e:
            self.report("hang", f"POST {path.decode()}", str(e))

    def probe_state(self, port, what):
        start = time.monotonic()
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.settimeout(2)
            s.sendall(b"GET /state HTTP/1.1\r\nHost: x\r\n\r\n")
            data = b""
            while True:
                chunk = s.recv(65536)
                if not chunk:
                    break
                data += chunk
            s.close()
            head, _, body = data.partition(b"\r\n\r\n")
            if not head.startswith(b"HTTP/1.1 200") and not head.startswith(b"HTTP/1.1 503"):
                self.report("hang", f"GET /state after {what}", f"answer: {head[:80]!r}")
                return
            if head.startswith(b"HTTP/1.1 200"):
                doc = json.loads(body)
                if "run" not in doc or not isinstance(doc["run"], dict):
                    self.report("contract", f"GET /state after {what}", f"document: {body[:200]!r}")
        except (OSError, ValueError) as e:
            self.report("hang", f"GET /state after {what}", f"{e} after {time.monotonic() - start:.1f} s")

    def case_viewer(self, count, deadline):
        out = self.fresh("viewer_run")
        seq = os.path.join(self.work, "slow")
        if not os.path.isdir(seq):  # the fixture at a quarter of its rate: a paced run of ~4 s
            shutil.copytree(self.dataset, seq)
            for name in ("rgb.txt", "depth.txt", "groundtruth.txt"):
                p = os.path.join(seq, name)
                lines = []
                for line in open(p).read().splitlines():
                    if line and not line.startswith("#"):
                        fields = line.split()
                        fields[0] = f"{float(fields[0]) * 4:.6f}"
                        line = " ".join(fields)
                    lines.append(line)
                open(p, "w").write("\n".join(lines) + "\n")
        command = [self.binary, "--json", "run", "--dataset", seq, "--out", out, "--no-people-filter", "--pace",
                   "sensor", "--viewer", "--viewer-port", "0", "--viewer-pause-timeout", "2"]
        errlog = open(os.path.join(self.work, "viewer_run.err"), "w+")
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=errlog, cwd=self.work)
        port = None
        for _ in range(600):
            errlog.seek(0)
            for line in errlog.read().splitlines():
                if line.startswith("viewer: http://127.0.0.1:"):
                    port = int(line.split(":")[3].split("/")[0])
            if port or process.poll() is not None:
                break
            time.sleep(0.1)
        shown = " ".join(command)
        if not port:
            self.report("contract", shown, "no viewer URL on stderr")
            process.kill()
            return
        self.viewer_requests(port, count, deadline, process)
        try:
            out_text, _ = process.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            process.kill()
            self.report("hang", shown, "the run did not end within 60 s of the last request")
            return
        if process.returncode != 0:
            errlog.seek(0)
            self.report("exit code", shown, f"exit {process.returncode}: {errlog.read()[-300:]}")
        try:
            json.loads(out_text)
        except ValueError:
            self.report("contract", shown, "stdout is not one JSON document")
        self.check_run_dir(shown, out)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser.add_argument("--bin", default=os.path.join(root, "build", "apps", "crowdslam", "crowdslam"))
    parser.add_argument("--cases", type=int, default=300)
    parser.add_argument("--time-budget", type=float, default=600, help="seconds, fixtures included")
    parser.add_argument("--timeout", type=float, default=60, help="seconds per command")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--only", default=",".join(KINDS))
    parser.add_argument("--keep", help="work in this directory and keep it")
    args = parser.parse_args()
    kinds = [k for k in args.only.split(",") if k]
    unknown = [k for k in kinds if k not in KINDS]
    if unknown:
        parser.error(f"--only: unknown kinds {unknown} (expected {KINDS})")
    binary = os.path.abspath(args.bin)
    if not os.access(binary, os.X_OK):
        parser.error(f"--bin {binary}: not an executable (build the target crowdslam first)")
    start = time.monotonic()
    deadline = start + args.time_budget
    work = args.keep or tempfile.mkdtemp(prefix="crowdslam_fuzz_")
    os.makedirs(work, exist_ok=True)
    fuzzer = Fuzzer(binary, work, args.seed, args.timeout)
    try:
        fuzzer.prepare()
        file_kinds = [k for k in kinds if k != "viewer"]
        viewer_share = (args.cases if kinds == ["viewer"] else args.cases // 5) if "viewer" in kinds else 0
        file_cases = args.cases - viewer_share
        # The viewer's turn is kept for the last part of the budget.
        file_deadline = deadline - (min(20.0, args.time_budget / 3) if viewer_share else 0)
        i = 0
        while file_kinds and i < file_cases and time.monotonic() < file_deadline:
            kind = file_kinds[i % len(file_kinds)]
            getattr(fuzzer, f"case_{kind}")(i)
            i += 1
        if viewer_share:
            fuzzer.case_viewer(viewer_share, deadline)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    elapsed = time.monotonic() - start
    by_kind = ", ".join(f"{k} {n}" for k, n in sorted(fuzzer.counts.items()))
    print(f"fuzz_inputs: {fuzzer.cases} cases ({by_kind}) in {elapsed:.0f} s, seed {args.seed}: "
          f"{len(fuzzer.findings)} finding(s)")
    for what in sorted({f[0] for f in fuzzer.findings}):
        print(f"  {what}: {sum(1 for f in fuzzer.findings if f[0] == what)}")
    return 1 if fuzzer.findings else 0


if __name__ == "__main__":
    sys.exit(main())
