#!/usr/bin/env bash
# Saved maps (issue 12): one mapping run saves its map, then N localisation runs in that map over the same
# sequence. Reports per run: frames localised, first localised frame, relocalisations, ATE, throughput,
# and the RMS position difference to the mapping run's trajectory without any alignment (both are in the
# map's frame); then the medians, the map's save/load times and its size.
#   scripts/measure_localization.sh [-n RUNS] [-b BUILD_DIR] -- RUN_ARGS...
# Example:
#   scripts/measure_localization.sh -n 5 -- --dataset ../shared/data/bonn_crowd --settings config/Bonn.yaml
set -euo pipefail
cd "$(dirname "$0")/.."
runs=5
script=measure_localization
source scripts/lib/run_options.sh
parse_run_options "$@"
out=out/localization
rm -rf "$out"
mkdir -p "$out"
echo "mapping run (saves $out/map.db) ..."
"$bin" -q run "${run_args[@]}" --out "$out/mapping" --save-map "$out/map.db" >/dev/null
for ((k = 1; k <= runs; ++k)); do
  echo "localisation run $k/$runs ..."
  "$bin" -q run "${run_args[@]}" --out "$out/loc_$k" --load-map "$out/map.db" --localization >/dev/null
done
/usr/bin/python3 - "$out" "$runs" <<'PY'
import json, math, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
def poses(path):
    p = {}
    for line in open(path):
        if line.startswith('#') or not line.strip():
            continue
        v = line.split()
        p[round(float(v[0]), 6)] = tuple(map(float, v[1:4]))
    return p
m = json.load(open(f"{out}/mapping/run.json"))
saved = m["map"]["saved"]
live = poses(f"{out}/mapping/CameraTrajectory.txt")
print("mapping: ATE %.4f m, %.1f frames/s, map %d keyframes, %d points, %.2f MB, saved in %.0f ms" % (
    m["accuracy"]["ate_rmse_m"], m["summary"]["throughput_fps"], saved["keyframes"], saved["map_points"],
    saved["bytes"] / 1e6, saved["save_ms"]))
rows = []
for k in range(1, runs + 1):
    d = json.load(open(f"{out}/loc_{k}/run.json"))
    l, s = d["map"]["loaded"], d["summary"]
    est = poses(f"{out}/loc_{k}/CameraTrajectory.txt")
    common = [t for t in est if t in live]
    rms = math.sqrt(sum(sum((a - b) ** 2 for a, b in zip(est[t], live[t])) for t in common) / max(1, len(common)))
    row = dict(localized=100.0 * l["frames_localized"] / l["frames"], first=l["first_localized_frame"],
               reloc=l["relocalizations"], ate=d["accuracy"]["ate_rmse_m"], fps=s["throughput_fps"], diff=rms,
               load=l["load_ms"], kf=s["keyframes"], points=s["map_points"])
    rows.append(row)
    print("run %d: localised %.1f %% (first frame %s, %d relocalisations), ATE %.4f m, %.1f frames/s, "
          "RMS to the mapping run %.4f m, map loaded in %.0f ms, %d keyframes / %d points after" % (
          k, row["localized"], row["first"], row["reloc"], row["ate"], row["fps"], row["diff"], row["load"],
          row["kf"], row["points"]))
med = lambda key: statistics.median(r[key] for r in rows)
print("median of %d: localised %.1f %%, first frame %s, ATE %.4f m, RMS to the mapping run %.4f m, %.1f frames/s "
      "(mapping run %.1f), load %.0f ms" % (runs, med("localized"), med("first"), med("ate"), med("diff"), med("fps"),
                                          m["summary"]["throughput_fps"], med("load")))
PY
