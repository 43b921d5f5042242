#!/usr/bin/env bash
# Person-detector accuracy and speed on the MOT sequences in ../shared/data/mot, as a markdown table
# (docs/DETECTION.md). One command:
#   scripts/eval_detectors.sh [BUILD_DIR]        (default: build; needs the `crowdslam` binary and python3)
# Runs `crowdslam detect` (single OpenCV thread) + `crowdslam detect-eval` (IoU 0.5) for each model, input
# size and threshold setting below, per sequence and pooled over the three sequences. Timing column: the
# median detect() time per frame (forward pass, decoding, NMS), the median of the three sequences' medians;
# the machine's load average is printed under the table (a shared CPU makes the times noisy).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$repo/build}"
cli="$build/apps/crowdslam/crowdslam"
mot="${CROWDSLAM_SHARED:-$repo/../shared}/data/mot"
[[ -x "$cli" ]] || { echo "eval_detectors: error: $cli not built" >&2; exit 1; }
[[ -d "$mot" ]] || { echo "eval_detectors: error: $mot missing" >&2; exit 1; }
sequences=(TUD-Campus TUD-Stadtmitte PETS09-S2L1-first150)
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# model input confidence nms [raw]. Inputs: square (160, 320, 416), aspect-true for the 4:3 MOT and
# Bonn frames (320x256, 416x320) and a 16:9 one (416x256: what a wide camera would use; letterboxed 4:3
# frames fill 341 of its 416 columns). Threshold sets: Crowd-SLAM's (0.2 / 0.1) and the usual
# YOLO ones (0.3 / 0.45). Darknet models stretch to the input, YOLOX models letterbox (model_zoo.cpp).
# EVAL_CONFIGS="body 160 0.2 0.1;yolox 416x320 0.3 0.45" replaces the list (e.g. for a quick check).
configs=()
for model in body coco yolox bytetrack; do
  for input in 160 320 416 320x256 416x320 416x256; do
    configs+=("$model $input 0.2 0.1" "$model $input 0.3 0.45")
  done
done
# Boxes before NMS, as the SLAM filter uses them by default with depth or stereo (Detector.filter_before_nms).
configs+=("body 160 0.2 0.1 raw" "yolox 416x320 0.3 0.45 raw" "bytetrack 416x320 0.3 0.45 raw")
if [[ -n "${EVAL_CONFIGS:-}" ]]; then IFS=';' read -r -a configs <<<"$EVAL_CONFIGS"; fi

results="$work/results.jsonl"
for config in "${configs[@]}"; do
  read -r model size conf nms raw <<<"$config"
  for seq in "${sequences[@]}"; do
    det="$work/det.txt"
    extra=()
    [[ "${raw:-}" == raw ]] && extra=(--raw)
    run=$("$cli" --json --quiet detect --dataset "$mot/$seq" --out "$det" --model "$model" --input "$size" \
      --confidence "$conf" --nms "$nms" --threads 1 "${extra[@]}")
    ev=$("$cli" --json --quiet detect-eval --gt "$mot/$seq/gt/gt.txt" --det "$det")
    printf '{"config":"%s","sequence":"%s","run":%s,"eval":%s}\n' "$config" "$seq" \
      "$(echo "$run" | tr -d '\n')" "$(echo "$ev" | tr -d '\n')" >>"$results"
  done
done
for seq in "${sequences[@]}"; do
  ev=$("$cli" --json --quiet detect-eval --gt "$mot/$seq/gt/gt.txt" --det "$mot/$seq/det/det.txt")
  printf '{"config":"public","sequence":"%s","run":null,"eval":%s}\n' "$seq" "$(echo "$ev" | tr -d '\n')" >>"$results"
done

python3 - "$results" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
seqs = []
for r in rows:
    if r["sequence"] not in seqs: seqs.append(r["sequence"])
def pct(x): return "-" if x is None else f"{100*x:.1f}"
def metrics(tp, fp, fn, iou_sum):
    n = tp + fn
    return (tp/(tp+fp) if tp+fp else None, tp/n if n else None, 1-(fn+fp)/n if n else None, iou_sum/tp if tp else None)
print("| model | input | resize | conf | NMS | boxes | " + " | ".join(f"{s} P / R / MODA / MODP" for s in seqs) +
      " | all P / R / MODA / MODP | ms/frame |")
print("|---|---|---|---|---|---|" + "---|" * len(seqs) + "---|---|")
configs = []
for r in rows:
    if r["config"] not in configs: configs.append(r["config"])
for c in configs:
    rs = [r for r in rows if r["config"] == c]
    cells, tp, fp, fn, iou, medians, resize = [], 0, 0, 0, 0.0, [], "-"
    for s in seqs:
        e = next(r for r in rs if r["sequence"] == s)["eval"]
        cells.append(" / ".join(pct(e[k]) for k in ("precision", "recall", "moda", "modp")))
        tp += e["tp"]; fp += e["fp"]; fn += e["fn"]
        iou += (e["modp"] or 0) * e["tp"]
    for r in rs:
        if r["run"]:
            medians.append(r["run"]["median_time_ms"]); resize = r["run"].get("resize", "-")
    allm = " / ".join(pct(x) for x in metrics(tp, fp, fn, iou))
    if c == "public":
        head = "MOT15 public det/det.txt | - | - | all | - | after NMS"
    else:
        p = c.split()
        head = f"{p[0]} | {p[1]} | {resize} | {p[2]} | {p[3]} | {'before NMS' if len(p) > 4 else 'after NMS'}"
    ms = f"{sorted(medians)[len(medians) // 2]:.1f}" if medians else "-"
    print(f"| {head} | " + " | ".join(cells) + f" | {allm} | {ms} |")
PY
echo
echo "(measured $(date -u '+%Y-%m-%d %H:%M UTC'), load average $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores)"
