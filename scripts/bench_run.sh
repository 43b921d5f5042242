#!/usr/bin/env bash
# N threaded runs of one `crowdslam run` command line and their medians (the way the project reports
# results: median of 5 runs of the threaded mode), through the evaluation workflow: a one-case matrix
# (timing mode: one run at a time) written to out/bench/matrix.yaml and run by Snakemake, so each run is
# a workflow job with its own directory, time.json and the table of workflows/README.md.
#   scripts/bench_run.sh [-n RUNS] [-b BUILD_DIR] -- RUN_ARGS...
# Example:
#   scripts/bench_run.sh -n 5 -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
# RUN_ARGS must include --dataset; --settings and every other option are passed on. Prints one line per
# run and the case's medians; the runs are in out/bench/bench/run.default.run/K/, the table in
# out/bench/bench/table.md. A rerun with the same binary and arguments reuses the finished runs (delete
# out/bench to measure again).
set -euo pipefail
cd "$(dirname "$0")/.."
runs=5
script=bench_run
source scripts/lib/run_options.sh
parse_run_options "$@"
command -v snakemake >/dev/null || { echo "$script: snakemake not installed (scripts/setup.sh)" >&2; exit 1; }
out=out/bench
mkdir -p "$out"
/usr/bin/python3 - "$out/matrix.yaml" "$runs" "${run_args[@]}" <<'PY'
import os, shlex, sys
path, runs, args = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
dataset, settings, rest, i = None, None, [], 0
while i < len(args):
    if args[i] in ("--dataset", "-d", "--settings", "-s") and i + 1 < len(args):
        if args[i] in ("--dataset", "-d"):
            dataset = args[i + 1]
        else:
            settings = args[i + 1]
        i += 2
        continue
    if args[i] == "--sequential":
        sys.exit("bench_run: runs are threaded (timing mode); --sequential is not allowed here")
    if args[i] in ("--out", "-o", "--overwrite"):
        sys.exit(f"bench_run: {args[i]} is set by the workflow")
    rest.append(args[i])
    i += 1
if not dataset:
    sys.exit("bench_run: give --dataset DIR among RUN_ARGS")
q = lambda s: "'" + s.replace("'", "''") + "'"
lines = ["matrix: bench", "title: \"scripts/bench_run.sh\"", "mode: timing", f"runs: {runs}", "datasets:",
         "  run:", f"    path: {q(os.path.abspath(dataset))}"]
if settings:
    lines.append(f"    settings: {q(os.path.abspath(settings))}")
if rest:
    lines.append(f"    args: {q(shlex.join(rest))}")
lines += ["options:", "  run: \"\""]
with open(path, "w") as f:
    f.write("\n".join(lines) + "\n")
PY
snakemake -s workflows/Snakefile --configfile "$out/matrix.yaml" --cores 2 -q \
  --config results="$PWD/$out" crowdslam="$PWD/$bin" >"$out/snakemake.log" 2>&1 || {
  echo "$script: the workflow failed; see $out/snakemake.log and $out/bench/_logs/" >&2
  tail -n 20 "$out/snakemake.log" >&2
  exit 1
}
/usr/bin/python3 - "$out/bench" <<'PY'
import glob, json, os, statistics, sys
case = os.path.join(sys.argv[1], "run.default.run")
rows = []
for run in sorted(glob.glob(os.path.join(case, "[0-9]*")), key=lambda p: int(os.path.basename(p))):
    d = json.load(open(os.path.join(run, "run.json")))
    t = json.load(open(os.path.join(run, "time.json")))
    s, a = d["summary"], d.get("accuracy") or {}
    row = dict(ate=a.get("ate_rmse_m", float("nan")), kf_ate=a.get("ate_keyframes_rmse_m", float("nan")),
               tracked=s["tracked_percent"], fps=s["throughput_fps"], track_med=s["tracking_ms_median"],
               track_p95=s["tracking_ms_p95"], total_med=s["total_ms_median"], total_p95=s["total_ms_p95"],
               extract_med=s["extraction_ms_median"], kf=s["keyframes"], cpu_ms=1000 * t["cpu_s"] / s["frames"],
               rss_mb=t["peak_rss_kb"] / 1024.0)
    rows.append(row)
    print("run %s: ATE %.4f m (keyframes %.4f m)  tracked %.1f %%  %.1f frames/s  tracking median %.2f ms "
          "p95 %.2f ms  total median %.2f ms p95 %.2f ms  keyframes %d  CPU %.1f ms/frame  peak RSS %.0f MB" %
          (os.path.basename(run), row["ate"], row["kf_ate"], row["tracked"], row["fps"], row["track_med"],
           row["track_p95"], row["total_med"], row["total_p95"], row["kf"], row["cpu_ms"], row["rss_mb"]))
if not rows:
    sys.exit("bench_run: no finished run in " + case)
med = {key: statistics.median(r[key] for r in rows) for key in rows[0]}
print("median of %d: ATE %.4f m (keyframes %.4f m)  tracked %.1f %%  %.1f frames/s  tracking median %.2f ms "
      "p95 %.2f ms  total median %.2f ms p95 %.2f ms  extraction median %.2f ms  CPU %.1f ms/frame  "
      "peak RSS %.0f MB" %
      (len(rows), med["ate"], med["kf_ate"], med["tracked"], med["fps"], med["track_med"], med["track_p95"],
       med["total_med"], med["total_p95"], med["extract_med"], med["cpu_ms"], med["rss_mb"]))
PY
