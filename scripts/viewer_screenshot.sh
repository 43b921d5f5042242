#!/usr/bin/env bash
# The README's picture of the live viewer (docs/viewer.png): a run with --viewer at the sensor's rate,
# paused by a headless Chromium page after AFTER updates and photographed live through Chromium's
# DevTools protocol (scripts/lib/cdp_screenshot.py), then stopped with SIGINT (its outputs go to
# out/viewer_screenshot/).
#   scripts/viewer_screenshot.sh [-a AFTER] [-o PNG] [-b BUILD_DIR] -- RUN_ARGS...
# Example: scripts/viewer_screenshot.sh -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
set -euo pipefail
cd "$(dirname "$0")/.."
after=60
png=docs/viewer.png
while [[ "${1:-}" == -a || "${1:-}" == -o ]]; do
  if [[ "$1" == -a ]]; then after=$2; else png=$2; fi
  shift 2
done
script=viewer_screenshot
source scripts/lib/run_options.sh
parse_run_options "$@"
out=out/viewer_screenshot
rm -rf "$out"
mkdir -p "$out"
port=8766
chromium_args=(--headless=new --no-sandbox --disable-gpu --enable-unsafe-swiftshader --use-angle=swiftshader
  --no-first-run --hide-scrollbars --window-size=1400,900)
"$bin" -q run "${run_args[@]}" --out "$out/run" --viewer --viewer-port "$port" --pace sensor 2>"$out/run.log" &
run=$!
trap 'kill "$run" "${browser:-}" 2>/dev/null || true' EXIT
state() { curl -s "http://127.0.0.1:$port/state" || true; }
for _ in $(seq 100); do [[ -n "$(state)" ]] && break; sleep 0.2; done
devtools=9339
timeout 300 chromium "${chromium_args[@]}" --remote-debugging-port=$devtools --user-data-dir="$out/profile" \
  "http://127.0.0.1:$port/?click=pause&after=$after" >/dev/null 2>&1 &
browser=$!
echo "viewer_screenshot: waiting for the page to pause the run after $after updates"
for _ in $(seq 600); do
  if state | grep -q '"paused":true'; then break; fi
  if ! kill -0 "$run" 2>/dev/null; then echo "viewer_screenshot: the run ended first" >&2; exit 1; fi
  sleep 0.2
done
sleep 1.5  # the page's last update applied and drawn
/usr/bin/python3 scripts/lib/cdp_screenshot.py "$devtools" "$out/viewer.png" "http://127.0.0.1:$port/"
[[ -s "$out/viewer.png" ]] || { echo "viewer_screenshot: no screenshot" >&2; exit 1; }
cp "$out/viewer.png" "$png"
echo "viewer_screenshot: $png ($(state | head -c 200))"
kill -INT "$run"
wait "$run" || true
