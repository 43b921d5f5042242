#!/usr/bin/python3
"""Measures crowdslam's headline results and writes docs/RESULTS.md and the README's results table.

Run through scripts/results.sh (which builds the CLI first). Each row is N threaded runs of
`crowdslam run` (default 5); the table gives the medians. The measured figures are kept in
docs/results.json, so `--only ROW` re-measures one row and the documents are rendered from all rows,
each with its own date. `--build-times` clones the checkout afresh and times scripts/demo.sh and
scripts/test.sh in it (ccache disabled), the figures a new user waits for; `--all` does both.
"""
import argparse
import datetime
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("CROWDSLAM_SHARED", os.path.join(REPO, "..", "shared"))
DATA = "../shared/data"  # as written in the commands shown to readers
BONN = [f"--dataset", f"{DATA}/bonn_crowd", "--settings", "config/Bonn.yaml"]
KITTI = ["--dataset", f"{DATA}/kitti07_head", "--settings", "config/KITTI04-12.yaml", "--sensor", "mono",
         "--no-people-filter", "--allow-untracked"]
SYNTH_CROWD = ["--frames", "300", "--people", "3", "--seed", "1", "--sprites", "none"]  # the box people
SYNTH_ROOM = ["--frames", "300"]

# name, sequence, setting, run arguments, synthetic sequence (synth arguments) or None
ROWS = [
    ("bonn_rgbd", "Bonn `rgbd_bonn_crowd` (927 frames)", "RGB-D, defaults (people filter, geometric check)", BONN, None),
    ("bonn_geometry", "Bonn `rgbd_bonn_crowd`", "RGB-D, `--no-people-filter` (geometric check alone)",
     BONN + ["--no-people-filter"], None),
    ("bonn_neither", "Bonn `rgbd_bonn_crowd`", "RGB-D, `--no-people-filter --geometry off` (static world)",
     BONN + ["--no-people-filter", "--geometry", "off"], None),
    ("bonn_yolox", "Bonn `rgbd_bonn_crowd`", "RGB-D, `--detector yolox --detector-mode latest --detector-interval 6`",
     BONN + ["--detector", "yolox", "--detector-mode", "latest", "--detector-interval", "6"], None),
    ("bonn_mono", "Bonn `rgbd_bonn_crowd`", "monocular (`--sensor mono`), Sim3-aligned", BONN + ["--sensor", "mono"],
     None),
    ("euroc_stereo", "EuRoC V1_01, first 95 pairs", "stereo, rectified from sensor.yaml",
     ["--dataset", f"{DATA}/euroc_v101_micro", "--settings", "config/EuRoC.yaml"], None),
    ("kitti_mono", "KITTI 07, first 100 frames (54 m)", "monocular, ground held in the final global BA", KITTI, None),
    ("kitti_mono_noground", "KITTI 07, first 100 frames", "monocular, `--ground off`", KITTI + ["--ground", "off"],
     None),
    ("synth_crowd_rgbd", "synthetic room, 3 people (300 frames)", "RGB-D, generator's boxes (`--detections`)",
     ["--detections", "{seq}/people_gt.txt"], SYNTH_CROWD),
    ("synth_room_mono", "synthetic room, empty (300 frames)", "monocular, `--no-people-filter`",
     ["--no-people-filter", "--sensor", "mono"], SYNTH_ROOM),
]

STATE = os.path.join(REPO, "docs", "results.json")
RESULTS_MD = os.path.join(REPO, "docs", "RESULTS.md")
README = os.path.join(REPO, "README.md")
BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"


def log(message):
    print(f"results: {message}", file=sys.stderr, flush=True)


def command_line(args):
    return " ".join(a if re.fullmatch(r"[\w./:=,@+-]+", a) else f"'{a}'" for a in args)


def machine():
    cpu = "unknown CPU"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    with open("/proc/meminfo") as f:
        mem_gb = int(f.readline().split()[1]) / 1024 / 1024
    debian = open("/etc/debian_version").read().strip() if os.path.exists("/etc/debian_version") else "?"
    gxx = subprocess.run(["g++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    return f"{cpu}, {os.cpu_count()} cores, {mem_gb:.0f} GB RAM, Debian {debian}, Linux {platform.release()}, {gxx}"


def git_commit():
    r = subprocess.run(["git", "-C", REPO, "rev-parse", "--short=12", "HEAD"], capture_output=True, text=True)
    return r.stdout.strip() or "unknown"


def synth_sequence(cli, name, synth_args, out_root):
    seq = os.path.join(out_root, "seq", name)
    if not os.path.exists(os.path.join(seq, "groundtruth.txt")):
        log(f"rendering {seq}")
        subprocess.run([cli, "-q", "synth", "--out", seq, "--force"] + synth_args, check=True)
    return seq


def measure_row(cli, row, runs, out_root):
    name, sequence, setting, run_args, synth_args = row
    shown = ["scripts/bench_run.sh", "-n", str(runs), "--"]
    if synth_args is not None:
        seq = synth_sequence(cli, name, synth_args, out_root)
        args = ["--dataset", seq] + [a.replace("{seq}", seq) for a in run_args]
        shown_args = ["--dataset", "S"] + [a.replace("{seq}", "S") for a in run_args]
        command = f"crowdslam synth --out S {command_line(synth_args)}; " + command_line(shown + shown_args)
    else:
        args = run_args
        command = command_line(shown + run_args)
    per_run = []
    for k in range(1, runs + 1):
        out = os.path.join(out_root, name, f"run_{k}")
        shutil.rmtree(out, ignore_errors=True)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        rss_file = out + ".rss"
        start = time.monotonic()
        r = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", rss_file, cli, "-q", "run"] + args +
                           ["--out", out], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if r.returncode != 0:
            raise SystemExit(f"results: {name} run {k} failed (exit {r.returncode}): {r.stderr.strip()[-500:]}")
        doc = json.load(open(os.path.join(out, "run.json")))
        s, a = doc["summary"], doc.get("accuracy") or {}
        run = {"ate_m": a.get("ate_rmse_m"), "tracked_percent": s["tracked_percent"], "map_resets": s["map_resets"],
               "fps": s["throughput_fps"], "total_ms_median": s["total_ms_median"], "total_ms_p95": s["total_ms_p95"],
               "keyframes": s["keyframes"], "rss_mb": int(open(rss_file).read().split()[-1]) / 1024.0,
               "wall_s": time.monotonic() - start}
        per_run.append(run)
        ate = "n/a" if run["ate_m"] is None else f"{run['ate_m']:.4f} m"
        log(f"{name} run {k}/{runs}: ATE {ate}, tracked {run['tracked_percent']:.1f} %, "
            f"{run['map_resets']} map resets, {run['fps']:.1f} frames/s")
    med = {}
    for key in per_run[0]:
        values = [r[key] for r in per_run if r[key] is not None]
        med[key] = statistics.median(values) if values else None
    return {"sequence": sequence, "setting": setting, "command": command, "runs": per_run, "median": med,
            "date": datetime.date.today().isoformat(), "commit": git_commit()}


def timed_lines(command, cwd, env, marks):
    """Runs command, echoing its output; returns the total seconds and, per mark regex, when it first showed."""
    start = time.monotonic()
    seen = {}
    p = subprocess.Popen(command, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    for line in p.stdout:
        sys.stderr.write(line)
        for key, pattern in marks.items():
            if key not in seen and re.search(pattern, line):
                seen[key] = time.monotonic() - start
    if p.wait() != 0:
        raise SystemExit(f"results: {' '.join(command)} failed in {cwd}")
    return time.monotonic() - start, seen


def measure_build_times(fresh):
    log(f"fresh clone in {fresh} (ccache disabled)")
    subprocess.run(["git", "clone", "-q", "--no-local", REPO, fresh], check=True)
    env = dict(os.environ, CCACHE_DISABLE="1", CROWDSLAM_SHARED=os.path.abspath(SHARED))
    demo_s, demo_marks = timed_lines(["bash", "scripts/demo.sh"], fresh, env,
                                     {"cli_built": r"setup: default vocabulary", "result": r"^ATE RMSE"})
    test_s, test_marks = timed_lines(["bash", "scripts/test.sh"], fresh, env, {"suite_start": r"^Test project"})
    return {"date": datetime.date.today().isoformat(), "commit": git_commit(),
            "demo_total_s": demo_s, "demo_cli_built_s": demo_marks.get("cli_built"),
            "demo_result_s": demo_marks.get("result"), "test_total_s": test_s,
            "test_build_s": test_marks.get("suite_start"),
            "suite_s": test_s - test_marks["suite_start"] if "suite_start" in test_marks else None}


def fmt(value, pattern, missing="n/a"):
    return missing if value is None else pattern.format(value)


def table(state):
    lines = ["| sequence | sensor, setting | ATE RMSE (m) | tracked | map resets | frames/s | command |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for name, *_ in ROWS:
        r = state["rows"].get(name)
        if r is None:
            continue
        m = r["median"]
        lines.append(f"| {r['sequence']} | {r['setting']} | {fmt(m['ate_m'], '{:.4f}')} | "
                     f"{m['tracked_percent']:.1f} % | {m['map_resets']:g} | {m['fps']:.1f} | `{r['command']}` |")
    return "\n".join(lines)


def minutes(seconds):
    return "n/a" if seconds is None else f"{seconds / 60:.1f} min ({seconds:.0f} s)"


def render(state):
    out = ["# Results", "",
           "Generated by `scripts/results.sh`; do not edit by hand (`scripts/results.sh --only ROW` re-measures one "
           "row, `--build-times` the setup and build times). Measured figures are kept in `docs/results.json`.", "",
           f"Machine: {state['machine']}. No GPU.", "",
           "Every row is the median of its threaded runs (`crowdslam run`, unpaced: every frame is processed as fast "
           "as the system goes, the mapper keeping up). ATE is the RMSE of every tracked frame after SE3 alignment "
           "(Sim3 for monocular), computed as TUM's `evaluate_ate.py`.", "", "## Headline table", "", table(state), "",
           "For comparison, the Crowd-SLAM paper (Soares et al., J. Intell. Robot. Syst. 2021) reports on "
           "`rgbd_bonn_crowd`: ORB-SLAM2 0.963 m, DynaSLAM 0.016 m, Crowd-SLAM 0.018 m (their machines, RGB-D).", "",
           "## Per row", ""]
    for name, *_ in ROWS:
        r = state["rows"].get(name)
        if r is None:
            continue
        m = r["median"]
        out += [f"### {name}: {r['sequence']}, {r['setting']}", "",
                f"Measured {r['date']} at commit {r['commit']}: `{r['command']}`", "",
                f"- median of {len(r['runs'])}: ATE {fmt(m['ate_m'], '{:.4f} m')}, tracked {m['tracked_percent']:.1f} %, "
                f"{m['map_resets']:g} map resets, {m['fps']:.1f} frames/s, per frame {m['total_ms_median']:.2f} ms "
                f"median / {m['total_ms_p95']:.2f} ms p95, {m['keyframes']:g} keyframes, peak RSS {m['rss_mb']:.0f} MB",
                "- runs: " + "; ".join(
                    f"{fmt(x['ate_m'], '{:.4f} m')}, {x['tracked_percent']:.1f} %, {x['map_resets']} resets, "
                    f"{x['fps']:.1f} frames/s" for x in r["runs"]), ""]
    b = state.get("build_times")
    out += ["## Setup and build times", ""]
    if b is None:
        out += ["Not measured yet: `scripts/results.sh --build-times`.", ""]
    else:
        out += [f"Measured {b['date']} at commit {b['commit']} on a fresh clone (`git clone`), with the Debian packages "
                "already installed and ccache disabled, by `scripts/results.sh --build-times`.", "",
                "| step | time |", "| --- | --- |",
                f"| `scripts/demo.sh`: the CLI built | {minutes(b['demo_cli_built_s'])} |",
                f"| `scripts/demo.sh`: first result (ATE printed) | {minutes(b['demo_result_s'])} |",
                f"| `scripts/test.sh`: build of the rest (tests, benchmarks, Python) | {minutes(b['test_build_s'])} |",
                f"| `scripts/test.sh`: the whole suite (CTest) | {minutes(b['suite_s'])} |",
                f"| `scripts/test.sh` in all | {minutes(b['test_total_s'])} |", ""] + (
                [f"({b['note']}.)", ""] if b.get("note") else []) + [
                "Installing the missing Debian packages (apt) on a fresh Debian 12 machine adds about 1.5 minutes "
                "to the first of these.", ""]
    return "\n".join(out)


def write_readme_table(state):
    text = open(README).read()
    if BEGIN not in text or END not in text:
        log(f"README.md has no {BEGIN} ... {END} block: its table is not updated")
        return
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(README, "w") as f:
        f.write(head + BEGIN + "\n" + table(state) + "\n" + END + tail)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", "--runs", type=int, default=5)
    parser.add_argument("--build-dir", default=os.path.join(REPO, "build"))
    parser.add_argument("--only", help="comma-separated row names: " + ", ".join(r[0] for r in ROWS))
    parser.add_argument("--build-times", action="store_true",
                        help="time demo.sh and test.sh on a fresh clone instead of measuring the rows (with --only: both)")
    parser.add_argument("--all", action="store_true", help="every row and the build times")
    parser.add_argument("--render", action="store_true", help="only render the documents from docs/results.json")
    args = parser.parse_args()
    names = [r[0] for r in ROWS]
    only = names if not args.only else args.only.split(",")
    unknown = [n for n in only if n not in names]
    if unknown:
        parser.error(f"unknown row(s) {', '.join(unknown)}; rows: {', '.join(names)}")
    state = json.load(open(STATE)) if os.path.exists(STATE) else {"rows": {}}
    fresh = None
    if not args.render and (args.build_times or args.all):
        # First, so that the rows can be measured with the fresh clone's own build (the same commit).
        # Beside this checkout, so that ../shared is found as in any checkout.
        fresh = tempfile.mkdtemp(prefix="crowdslam-fresh-", dir=os.path.dirname(REPO))
        state["build_times"] = measure_build_times(fresh)
        args.build_dir = os.path.join(fresh, "build")
    if not args.render:
        cli = os.path.join(args.build_dir, "apps", "crowdslam", "crowdslam")
        if not os.access(cli, os.X_OK):
            raise SystemExit(f"results: {cli} is not built (scripts/setup.sh --target crowdslam)")
        if not os.path.isdir(SHARED):
            raise SystemExit(f"results: {SHARED} not found (set CROWDSLAM_SHARED)")
        out_root = os.path.join(REPO, "out", "results")
        measure_rows = args.all or args.only or not args.build_times
        for row in ROWS:
            if measure_rows and row[0] in only:
                log(f"{row[0]}: {args.runs} runs")
                state["rows"][row[0]] = measure_row(cli, row, args.runs, out_root)
                state["machine"] = machine()
                json.dump(state, open(STATE, "w"), indent=1)
    if fresh:
        shutil.rmtree(fresh, ignore_errors=True)
    state["machine"] = state.get("machine") or machine()
    json.dump(state, open(STATE, "w"), indent=1)
    with open(RESULTS_MD, "w") as f:
        f.write(render(state) + "\n")
    write_readme_table(state)
    log(f"wrote {RESULTS_MD} and the README table")


if __name__ == "__main__":
    main()
