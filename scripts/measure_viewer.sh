#!/usr/bin/env bash
# Throughput with the live viewer (issue 13): N runs without --viewer and N with --viewer and a headless
# Chromium connected to it (on this same machine), alternating; prints each run, the browser's CPU time
# by process and thread (scripts/lib/process_cpu.py) and the medians.
#   scripts/measure_viewer.sh [-w] [-p PAGE_QUERY] [-n RUNS] [-b BUILD_DIR] -- RUN_ARGS...
# PAGE_QUERY (diagnostics) is appended to the page's URL, e.g. -p norender=1.
# -w: the viewer page already open, as a user keeps it: Chromium loads it from a short run (150 frames at
# the sensor rate) on the same port, and the page reconnects by itself to the measured run; its CPU
# counts from the measured run's start. Without -w the browser starts with the run, and its start-up
# (about 2.7 CPU seconds) and the page's loading fall inside the run.
# Example: scripts/measure_viewer.sh -n 3 -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
set -euo pipefail
cd "$(dirname "$0")/.."
runs=3
script=measure_viewer
query=
warm=0
if [[ "${1:-}" == "-w" ]]; then warm=1; shift; fi
if [[ "${1:-}" == "-p" ]]; then query="?$2"; shift 2; fi
source scripts/lib/run_options.sh
parse_run_options "$@"
out=out/viewer
rm -rf "$out"
mkdir -p "$out"
port=8765
for ((k = 1; k <= runs; ++k)); do
  "$bin" -q run "${run_args[@]}" --out "$out/plain_$k" >/dev/null
  chromium_args=(--headless=new --no-sandbox --disable-gpu --enable-unsafe-swiftshader --use-angle=swiftshader
    --no-first-run --remote-debugging-port=0 --user-data-dir="$out/profile_$k")
  url="http://127.0.0.1:$port/$query"
  if ((warm)); then
    # The page open before the run, as a user keeps it: it is loaded from a short run on the same port
    # and reconnects by itself to the measured run's server (the page follows the next run).
    "$bin" -q run "${run_args[@]}" --out "$out/prime_$k" --viewer --viewer-port "$port" --frames 150 --pace sensor \
      >/dev/null 2>"$out/prime_$k.log" &
    prime=$!
    sleep 0.5
    timeout 600 chromium "${chromium_args[@]}" "$url" >/dev/null 2>&1 &
    browser=$!
    wait "$prime"
  fi
  "$bin" -q run "${run_args[@]}" --out "$out/viewer_$k" --viewer --viewer-port "$port" >/dev/null 2>"$out/viewer_$k.log" &
  pid=$!
  if ((warm)); then
    /usr/bin/python3 scripts/lib/process_cpu.py "$browser" "$out/browser_cpu_$k.json" --since-start --interval 3600 &
  else
    sleep 0.5
    timeout 600 chromium "${chromium_args[@]}" "$url" >/dev/null 2>&1 &
    browser=$!
    /usr/bin/python3 scripts/lib/process_cpu.py "$browser" "$out/browser_cpu_$k.json" --interval 1 &
  fi
  sampler=$!
  wait "$pid"
  kill "$sampler" 2>/dev/null || true
  wait "$sampler" 2>/dev/null || true
  kill "$browser" 2>/dev/null || true
  wait "$browser" 2>/dev/null || true
done
/usr/bin/python3 - "$out" "$runs" <<'PY'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
fps = lambda d: json.load(open(d + "/run.json"))["summary"]["throughput_fps"]
plain = [fps(f"{out}/plain_{k}") for k in range(1, runs + 1)]
viewer = [fps(f"{out}/viewer_{k}") for k in range(1, runs + 1)]
wall = lambda d: json.load(open(d + "/run.json"))["summary"]["wall_time_s"]
for k in range(runs):
    cpu = json.load(open(f"{out}/browser_cpu_{k + 1}.json"))
    by_type = ", ".join("%s %.1f" % kv for kv in sorted(cpu["by_type"].items(), key=lambda kv: -kv[1]))
    print("pair %d: %.1f frames/s without the viewer, %.1f with a browser connected; browser CPU %.1f s in a %.1f s run (%s)"
          % (k + 1, plain[k], viewer[k], cpu["total_s"], wall(f"{out}/viewer_{k + 1}"), by_type))
    print("        busiest browser threads: " + ", ".join("%s %.1f" % kv for kv in list(cpu["by_thread"].items())[:6]))
p, v = statistics.median(plain), statistics.median(viewer)
print("median: %.1f without, %.1f with the viewer and a browser: %.1f %%" % (p, v, 100 * v / p))
PY
