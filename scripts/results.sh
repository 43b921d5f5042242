#!/usr/bin/env bash
# Measures the headline results (median of 5 threaded runs per row) and regenerates docs/RESULTS.md and
# the results table of README.md. Builds the CLI first (scripts/setup.sh --target crowdslam).
#   scripts/results.sh                     every row (about 15 minutes on 2 cores)
#   scripts/results.sh --only bonn_rgbd    one row (names: scripts/results.sh --help)
#   scripts/results.sh --build-times       demo.sh and test.sh timed on a fresh clone (about 30 minutes)
#   scripts/results.sh --all               both
#   scripts/results.sh -n 3 ...            another number of runs per row
# Data: ../shared (or $CROWDSLAM_SHARED). Runs go to out/results/.
set -euo pipefail
cd "$(dirname "$0")/.."
# --build-times and --all build in their own fresh clone (and measure the rows with its build).
for arg in "$@"; do
  case "$arg" in
    -h | --help | --render | --build-times | --all) exec /usr/bin/python3 scripts/results.py "$@" ;;
  esac
done
bash scripts/setup.sh --target crowdslam build >&2
exec /usr/bin/python3 scripts/results.py "$@"
