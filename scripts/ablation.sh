#!/usr/bin/env bash
# People-filter ablation on bonn_crowd (like the Crowd-SLAM paper's Table 9): tracked frames and ATE
# (median of N threaded runs) for the filter off, the paper mode, our depth mode, and the feature-number
# update and box options switched one at a time.
#   scripts/ablation.sh [-n RUNS] [-b BUILD_DIR] [DATASET]      (default: 5 runs, build/, ../shared/data/bonn_crowd)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=5
build=build
while [[ $# -gt 0 ]]; do
  case "$1" in
    -n) runs="$2"; shift 2 ;;
    -b) build="$2"; shift 2 ;;
    *) break ;;
  esac
done
dataset="${1:-${CROWDSLAM_SHARED:-../shared}/data/bonn_crowd}"
dir=out/ablation
mkdir -p "$dir"
base=config/Bonn.yaml
variant() {  # name, sed expression on the base settings[, a settings line to append]
  sed -e "$2" "$base" > "$dir/$1.yaml"
  if [[ -n "${3:-}" ]]; then printf '%s\n' "$3" >> "$dir/$1.yaml"; fi
}
variant paper       's/^PeopleFilter.mode: .*/PeopleFilter.mode: "paper"/'
variant paper_nofnu 's/^PeopleFilter.mode: .*/PeopleFilter.mode: "paper"/; s/^FeatureBudget.enabled: .*/FeatureBudget.enabled: 0/'
variant paper_nms   's/^PeopleFilter.mode: .*/PeopleFilter.mode: "paper"/' 'Detector.filter_before_nms: 0'
variant depth       's/^PeopleFilter.mode: .*/PeopleFilter.mode: "depth"/'
variant depth_nofnu 's/^PeopleFilter.mode: .*/PeopleFilter.mode: "depth"/; s/^FeatureBudget.enabled: .*/FeatureBudget.enabled: 0/'
variant depth_union 's/^PeopleFilter.mode: .*/PeopleFilter.mode: "depth"/; s/^FeatureBudget.area: .*/FeatureBudget.area: "union"/'
variant depth_nms   's/^PeopleFilter.mode: .*/PeopleFilter.mode: "depth"/' 'Detector.filter_before_nms: 0'

echo "| variant | tracked % | ATE RMSE (m) | frames/s |"
echo "| --- | --- | --- | --- |"
row() {  # label, extra run args...
  local label="$1"; shift
  local line
  line=$(bash scripts/bench_run.sh -n "$runs" -b "$build" -- --dataset "$dataset" "$@" | tail -1)
  python3 - "$label" "$line" <<'PY'
import re, sys
label, line = sys.argv[1], sys.argv[2]
ate = re.search(r"ATE ([0-9.na]+) m", line).group(1)
tracked = re.search(r"tracked ([0-9.]+) %", line).group(1)
fps = re.search(r"([0-9.]+) frames/s", line).group(1)
print(f"| {label} | {tracked} | {ate} | {fps} |")
PY
}
row "filter off (static-world baseline)" --settings "$base" --no-people-filter
row "paper: boxes before NMS, FNU (sum area)" --settings "$dir/paper.yaml"
row "paper, FNU off" --settings "$dir/paper_nofnu.yaml"
row "paper, boxes after NMS" --settings "$dir/paper_nms.yaml"
row "depth mode, FNU (sum area) [default]" --settings "$dir/depth.yaml"
row "depth mode, FNU off" --settings "$dir/depth_nofnu.yaml"
row "depth mode, FNU union area" --settings "$dir/depth_union.yaml"
row "depth mode, boxes after NMS" --settings "$dir/depth_nms.yaml"
