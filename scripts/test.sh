#!/usr/bin/env bash
# Quick-start command 2: set up (packages, configure, build) and run the whole test suite.
#   scripts/test.sh [ctest args...]      e.g. scripts/test.sh -L unit
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh build
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 1200 "$@"
