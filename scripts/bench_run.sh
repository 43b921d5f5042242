#!/usr/bin/env bash
# Runs `crowdslam run` several times on one dataset and reports the median of the accuracy and speed
# figures (the way the project reports results: median of 5 runs of the threaded mode).
#   scripts/bench_run.sh [-n RUNS] [-b BUILD_DIR] -- RUN_ARGS...
# Example:
#   scripts/bench_run.sh -n 5 -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
# Prints one line per run and a summary line with the medians; the runs' outputs go to out/bench/run_K.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=5
script=bench_run
source scripts/lib/run_options.sh
parse_run_options "$@"
out=out/bench
mkdir -p "$out"
for ((k = 1; k <= runs; ++k)); do
  rm -rf "$out/run_$k"
  /usr/bin/time -f "%M" -o "$out/run_$k.rss" "$bin" -q run "${run_args[@]}" --out "$out/run_$k" >/dev/null
done
python3 - "$out" "$runs" <<'PY'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
rows = []
for k in range(1, runs + 1):
    d = json.load(open(f"{out}/run_{k}/run.json"))
    s, a = d["summary"], d.get("accuracy") or {}
    rss = int(open(f"{out}/run_{k}.rss").read().split()[-1]) / 1024.0
    row = dict(ate=a.get("ate_rmse_m", float("nan")), kf_ate=a.get("ate_keyframes_rmse_m", float("nan")),
               tracked=s["tracked_percent"], fps=s["throughput_fps"],
               track_med=s["tracking_ms_median"], track_p95=s["tracking_ms_p95"], total_med=s["total_ms_median"],
               total_p95=s["total_ms_p95"], extract_med=s["extraction_ms_median"], kf=s["keyframes"], rss_mb=rss)
    rows.append(row)
    print("run %d: ATE %.4f m (keyframes %.4f m)  tracked %.1f %%  %.1f frames/s  "
          "tracking median %.2f ms p95 %.2f ms  "
          "total median %.2f ms p95 %.2f ms  keyframes %d  peak RSS %.0f MB" %
          (k, row["ate"], row["kf_ate"], row["tracked"], row["fps"], row["track_med"], row["track_p95"],
           row["total_med"], row["total_p95"], row["kf"], row["rss_mb"]))
med = {key: statistics.median(r[key] for r in rows) for key in rows[0]}
print("median of %d: ATE %.4f m (keyframes %.4f m)  tracked %.1f %%  %.1f frames/s  "
      "tracking median %.2f ms p95 %.2f ms  "
      "total median %.2f ms p95 %.2f ms  extraction median %.2f ms  peak RSS %.0f MB" %
      (runs, med["ate"], med["kf_ate"], med["tracked"], med["fps"], med["track_med"], med["track_p95"],
       med["total_med"], med["total_p95"], med["extract_med"], med["rss_mb"]))
PY
