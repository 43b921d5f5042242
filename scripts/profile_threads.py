#!/usr/bin/python3
"""Where a threaded `crowdslam run` spends its CPU, by thread: sampled with `perf record -e cpu-clock`
(Debian's linux-perf) over the whole run, then split by thread name (crowdslam names its threads:
cs-reader, cs-detector, cs-mapper, cs-loop, cs-global-ba, cs-journal, cs-viewer; tracking is the main
thread, named after the program) and, within each thread, by library and by function.

  scripts/profile_threads.py [--bin BUILD/apps/crowdslam/crowdslam] [--out out/threads] [--top N]
                             [--report OUT/perf.data] -- RUN_ARGS...

RUN_ARGS go to `crowdslam run` (e.g. --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml).
Writes OUT/perf.data, OUT/threads.json and OUT/threads.md (the tables in docs/PROFILE.md), and prints
the tables. Shares are of all samples of the run (both cores), so they add up to 100 % across threads;
the seconds are samples / frequency. Functions of libraries without symbols (OpenCV, libjpeg) are
counted under their library.
"""
import argparse
import collections
import json
import os
import subprocess
import sys

FREQUENCY = 1999


def short(name):
    """A function's name without its namespace's anonymous part and its arguments, at most 60 characters."""
    return name.replace("(anonymous namespace)::", "").split("(")[0][:60]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    here = os.path.dirname(os.path.abspath(__file__))
    parser.add_argument("--bin", default=os.path.join(here, "..", "build", "apps", "crowdslam", "crowdslam"))
    parser.add_argument("--out", default="out/threads")
    parser.add_argument("--top", type=int, default=8, help="functions listed per thread")
    parser.add_argument("--report", help="only split an existing perf.data (recorded by this script)")
    parser.add_argument("run_args", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    run_args = [a for a in args.run_args if a != "--"]
    os.makedirs(args.out, exist_ok=True)
    data = args.report or os.path.join(args.out, "perf.data")
    if not args.report:
        if not run_args:
            sys.exit("profile_threads: give the run's arguments after --")
        run_out = os.path.join(args.out, "run")
        cmd = ["perf", "record", "-F", str(FREQUENCY), "-e", "cpu-clock", "-o", data, "--",
               args.bin, "run", *run_args, "--out", run_out, "--overwrite"]
        print("profile_threads:", " ".join(cmd), file=sys.stderr)
        if subprocess.run(cmd, stdout=subprocess.DEVNULL).returncode != 0:
            sys.exit("profile_threads: the run failed (see above)")
    # perf prints no symbol without the address field: "COMM ADDRESS SYMBOL (LIBRARY)".
    script = subprocess.run(["perf", "script", "-i", data, "-F", "comm,ip,sym,dso"], check=True,
                            capture_output=True, text=True).stdout
    program = os.path.basename(args.bin)[:15]
    by_thread = collections.Counter()
    by_function = collections.defaultdict(collections.Counter)
    for line in script.splitlines():
        parts = line.split(None, 2)
        if not parts:
            continue
        thread = "tracking (main)" if parts[0] == program else parts[0]
        rest = parts[2].strip() if len(parts) > 2 else ""
        # "symbol (library path)", or "[unknown] (library path)" for a library without symbols
        symbol, _, library = rest.rpartition(" (")
        library = os.path.basename(library.rstrip(")"))
        name = library if symbol in ("", "[unknown]") else symbol
        by_thread[thread] += 1
        by_function[thread][name] += 1
    total = sum(by_thread.values())
    if total == 0:
        sys.exit("profile_threads: no samples (is perf allowed here? see /proc/sys/kernel/perf_event_paranoid)")
    report = {"samples": total, "frequency_hz": FREQUENCY, "threads": []}
    lines = ["| thread | share of the run's CPU | CPU s | largest items (share of the run) |", "| --- | ---: | ---: | --- |"]
    for thread, count in by_thread.most_common():
        top = by_function[thread].most_common(args.top)
        report["threads"].append({"thread": thread, "samples": count,
                                  "functions": [{"name": n, "samples": c} for n, c in top]})
        items = "; ".join(f"{short(n)} {100.0 * c / total:.1f} %" for n, c in top[:4])
        lines.append(f"| {thread} | {100.0 * count / total:.1f} % | {count / FREQUENCY:.2f} | {items} |")
    with open(os.path.join(args.out, "threads.json"), "w") as f:
        json.dump(report, f, indent=1)
    with open(os.path.join(args.out, "threads.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
