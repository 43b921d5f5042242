#!/usr/bin/env bash
# Measures how a run ends on SIGINT: starts `crowdslam run`, sends SIGINT once its trajectory journal
# holds POSES poses, and reports the frames processed, the poses written, run.json's end state, and the
# time from the signal to the exit (all outputs written by then).
#   scripts/measure_interrupt.sh [-p POSES] [-n RUNS] [-s SIGNAL] [-b BUILD_DIR] -- RUN_ARGS...
# Example (the figure in README / docs/RESULTS.md):
#   scripts/measure_interrupt.sh -p 400 -n 5 -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
set -euo pipefail
cd "$(dirname "$0")/.."
poses=400
runs=1
signal=INT
build=build
while [[ $# -gt 0 && "$1" != "--" ]]; do
  case "$1" in
    -p) poses="$2"; shift 2 ;;
    -n) runs="$2"; shift 2 ;;
    -s) signal="$2"; shift 2 ;;
    -b) build="$2"; shift 2 ;;
    *) echo "measure_interrupt: unknown option $1" >&2; exit 2 ;;
  esac
done
[[ "${1:-}" == "--" ]] && shift
bin="$build/apps/crowdslam/crowdslam"
[[ -x "$bin" ]] || { echo "measure_interrupt: $bin not built (run scripts/setup.sh)" >&2; exit 1; }
out=out/interrupt
mkdir -p "$out"
for ((k = 1; k <= runs; ++k)); do
  dir="$out/run_$k"
  rm -rf "$dir"
  "$bin" -q run "$@" --out "$dir" >/dev/null 2>"$dir.log" &
  pid=$!
  while kill -0 "$pid" 2>/dev/null; do
    if [[ -f "$dir/CameraTrajectory.txt" ]] && (($(grep -vc '^#' "$dir/CameraTrajectory.txt") >= poses)); then break; fi
    sleep 0.01
  done
  journal=$(grep -vc '^#' "$dir/CameraTrajectory.txt" || true)
  sent=$(date +%s.%N)
  kill "-$signal" "$pid"
  rc=0
  wait "$pid" || rc=$?
  done_at=$(date +%s.%N)
  python3 - "$dir" "$journal" "$sent" "$done_at" "$rc" <<'PY'
import json, sys
d, journal, sent, done, rc = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
doc = json.load(open(f"{d}/run.json"))
lines = [l for l in open(f"{d}/CameraTrajectory.txt") if l.strip() and not l.startswith("#")]
s = doc["summary"]
print("journal %d poses at the signal -> %s, exit %d after %.3f s: %d frames, %d poses written (tracked %d)" %
      (journal, doc["end_state"], rc, done - sent, s["frames"], len(lines), s["tracked_frames"]))
PY
done
