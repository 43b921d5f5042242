#!/usr/bin/env bash
# Throughput with the live viewer (issue 13): N runs without --viewer and N with --viewer and a headless
# Chromium connected to it (on this same machine), alternating; prints each run and the medians.
#   scripts/measure_viewer.sh [-n RUNS] [-b BUILD_DIR] -- RUN_ARGS...
# Example: scripts/measure_viewer.sh -n 3 -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
set -euo pipefail
cd "$(dirname "$0")/.."
runs=3
script=measure_viewer
source scripts/lib/run_options.sh
parse_run_options "$@"
out=out/viewer
rm -rf "$out"
mkdir -p "$out"
port=8765
for ((k = 1; k <= runs; ++k)); do
  "$bin" -q run "${run_args[@]}" --out "$out/plain_$k" >/dev/null
  "$bin" -q run "${run_args[@]}" --out "$out/viewer_$k" --viewer --viewer-port "$port" >/dev/null 2>"$out/viewer_$k.log" &
  pid=$!
  sleep 0.5
  timeout 600 chromium --headless=new --no-sandbox --disable-gpu --enable-unsafe-swiftshader --use-angle=swiftshader \
    --no-first-run --remote-debugging-port=0 --user-data-dir="$out/profile_$k" "http://127.0.0.1:$port/" \
    >/dev/null 2>&1 &
  browser=$!
  wait "$pid"
  kill "$browser" 2>/dev/null || true
  wait "$browser" 2>/dev/null || true
done
/usr/bin/python3 - "$out" "$runs" <<'PY'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
fps = lambda d: json.load(open(d + "/run.json"))["summary"]["throughput_fps"]
plain = [fps(f"{out}/plain_{k}") for k in range(1, runs + 1)]
viewer = [fps(f"{out}/viewer_{k}") for k in range(1, runs + 1)]
for k in range(runs):
    print("pair %d: %.1f frames/s without the viewer, %.1f with a browser connected" % (k + 1, plain[k], viewer[k]))
p, v = statistics.median(plain), statistics.median(viewer)
print("median: %.1f without, %.1f with the viewer and a browser: %.1f %%" % (p, v, 100 * v / p))
PY
