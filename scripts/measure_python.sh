#!/usr/bin/env bash
# Throughput of Python-driven tracking against `crowdslam run` (issue 15): N runs of each, alternating
# (the machine is shared and noisy), same dataset, settings and threaded mode; prints each pair and the
# medians. The Python side is crowdslam.datasets.open + System.track in a plain loop, timed like run.json's
# throughput_fps (frames / wall time of the frame loop, before shutdown).
#   scripts/measure_python.sh [-n RUNS] [-b BUILD_DIR] -- RUN_ARGS...
# RUN_ARGS: --dataset DIR [--settings FILE] [--sensor S] [--frames N] [--no-people-filter] (given to both).
# Example: scripts/measure_python.sh -n 5 -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
set -euo pipefail
cd "$(dirname "$0")/.."
runs=5
script=measure_python
source scripts/lib/run_options.sh
parse_run_options "$@"
[[ -f "$build/python/crowdslam/__init__.py" ]] || { echo "$script: $build/python not built" >&2; exit 1; }
out=out/python
rm -rf "$out"
mkdir -p "$out"
for ((k = 1; k <= runs; ++k)); do
  "$bin" -q run "${run_args[@]}" --out "$out/cli_$k" >/dev/null
  PYTHONPATH="$build/python" /usr/bin/python3 - "$out/python_$k.json" "${run_args[@]}" <<'PY'
import argparse, json, sys, time
import crowdslam
parser = argparse.ArgumentParser()
parser.add_argument("--dataset", required=True)
parser.add_argument("--settings")
parser.add_argument("--sensor")
parser.add_argument("--frames", type=int, default=0)
parser.add_argument("--no-people-filter", action="store_true")
args, _ = parser.parse_known_args(sys.argv[2:])
seq = crowdslam.datasets.open(args.dataset)
sensor = args.sensor or seq.sensor
slam = crowdslam.System(args.settings or seq.settings_path, sensor=sensor, people_filter=not args.no_people_filter)
frames = 0
start = time.perf_counter()
for frame in seq:
    if args.frames and frames == args.frames:
        break
    slam.track(frame.image, frame.depth if sensor == "rgbd" else None, frame.right if sensor == "stereo" else None,
               timestamp=frame.timestamp)
    frames += 1
wall = time.perf_counter() - start
slam.shutdown()
json.dump({"frames": frames, "tracked": slam.stats()["tracked_frames"], "wall_time_s": wall,
           "throughput_fps": frames / wall}, open(sys.argv[1], "w"))
PY
done
/usr/bin/python3 - "$out" "$runs" <<'PY'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
cli = [json.load(open(f"{out}/cli_{k}/run.json"))["summary"] for k in range(1, runs + 1)]
py = [json.load(open(f"{out}/python_{k}.json")) for k in range(1, runs + 1)]
for k in range(runs):
    print("pair %d: CLI %.2f frames/s (%d tracked), Python %.2f frames/s (%d tracked)"
          % (k + 1, cli[k]["throughput_fps"], cli[k]["tracked_frames"], py[k]["throughput_fps"], py[k]["tracked"]))
c = statistics.median(s["throughput_fps"] for s in cli)
p = statistics.median(s["throughput_fps"] for s in py)
print("median: CLI %.2f frames/s, Python %.2f frames/s: Python at %.1f %% of the CLI" % (c, p, 100 * p / c))
PY
