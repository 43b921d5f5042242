#!/usr/bin/python3
"""One table per matrix from its run directories: median, min and max of each figure over the runs of
each case. Writes OUT.json (every run's figures, the statistics, where and when they were measured),
OUT.csv (one row per case, one column per figure and statistic) and OUT.md (median, with min-max).

  aggregate.py --matrix RESULTS/MATRIX/matrix.json --results RESULTS/MATRIX --out RESULTS/MATRIX/table

Only complete results count: a run directory with job.json (written last by run_job.py) and a run.json
whose end_state is "completed". Staging directories (CASE/RUN.tmp-PID) are never read.
Figures: from run.json (ATE, RPE, tracked %, map resets, frames/s, ...) and time.json (CPU time and peak
RSS measured by /usr/bin/time around the process: run.json holds neither).
"""
import argparse
import csv
import json
import os
import re
import statistics

# key, column title, format, where it comes from
FIGURES = [
    ("ate_m", "ATE RMSE (m)", "{:.4f}"),
    ("rpe_m_per_s", "RPE (m/s)", "{:.4f}"),
    ("rpe_deg_per_s", "RPE (deg/s)", "{:.3f}"),
    ("tracked_percent", "tracked %", "{:.1f}"),
    ("map_resets", "map resets", "{:g}"),
    ("fps", "frames/s", "{:.1f}"),
    ("cpu_s_per_frame", "CPU s/frame", "{:.4f}"),
    ("peak_rss_mb", "peak RSS (MB)", "{:.0f}"),
]
EXTRA = ["keyframes", "reanchors", "bridged_frames", "frames", "wall_s", "cpu_s"]
STATS = ("median", "min", "max")


def run_figures(run_dir):
    """The figures of one finished run, or None when the directory is not a complete result."""
    try:
        with open(os.path.join(run_dir, "job.json")) as f:
            job = json.load(f)
        with open(os.path.join(run_dir, "run.json")) as f:
            doc = json.load(f)
        with open(os.path.join(run_dir, "time.json")) as f:
            timing = json.load(f)
    except (OSError, ValueError):
        return None
    if doc.get("end_state") != "completed":
        return None
    s, a = doc.get("summary") or {}, doc.get("accuracy") or {}
    frames = s.get("frames") or 0
    fig = {"ate_m": a.get("ate_rmse_m", s.get("ate_rmse_m")), "rpe_m_per_s": a.get("rpe_trans_rmse_m_per_s"),
           "rpe_deg_per_s": a.get("rpe_rot_rmse_deg_per_s"), "tracked_percent": s.get("tracked_percent"),
           "map_resets": s.get("map_resets"), "fps": s.get("throughput_fps"),
           "cpu_s_per_frame": timing["cpu_s"] / frames if frames else None,
           "peak_rss_mb": timing["peak_rss_kb"] / 1024.0, "keyframes": s.get("keyframes"),
           "reanchors": s.get("reanchors"), "bridged_frames": s.get("bridged_frames"), "frames": frames,
           "wall_s": timing["wall_s"], "cpu_s": timing["cpu_s"]}
    return {"dir": run_dir, "figures": fig, "machine": job["machine"], "started": job["started"],
            "load_before": job.get("load_before"), "version": doc.get("crowdslam_version"),
            "commit": doc.get("git_commit")}


def stats(values):
    values = [v for v in values if v is not None]
    if not values:
        return {k: None for k in STATS}
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def run_dirs(case_dir):
    if not os.path.isdir(case_dir):
        return []
    return sorted((os.path.join(case_dir, n) for n in os.listdir(case_dir) if re.fullmatch(r"\d+", n)),
                  key=lambda p: int(os.path.basename(p)))


def machine_name(m):
    return f"{m['host']}: {m['cpu']}, {m['cores_usable']} of {m['cores']} cores, {m['mem_gb']} GB"


def provenance(runs):
    """Where and when the runs were measured, as the tables state it."""
    machines = sorted({machine_name(r["machine"]) for r in runs})
    dates = sorted(r["started"][:10] for r in runs)
    loads = [r["load_before"][0] for r in runs if r.get("load_before")]
    builds = sorted({f"{r['version']} ({r['commit']})" for r in runs})
    return {"machines": machines, "first": dates[0] if dates else None, "last": dates[-1] if dates else None,
            "load_1min": stats(loads), "builds": builds, "runs": len(runs)}


def fmt(value, pattern):
    return "n/a" if value is None else pattern.format(value)


def cell(st, pattern):
    if st["median"] is None:
        return "n/a"
    if st["min"] == st["max"]:
        return fmt(st["median"], pattern)
    return f"{fmt(st['median'], pattern)} ({fmt(st['min'], pattern)}-{fmt(st['max'], pattern)})"


def command_of(matrix):
    files = matrix.get("configfiles") or [f"workflows/matrices/{matrix['matrix']}.yaml"]
    return f"snakemake -s workflows/Snakefile --configfile {' '.join(files)} --cores 2"


def markdown(table):
    m = table["matrix"]
    p = table["provenance"]
    mode = ("sequential runs (`--sequential`, 1 thread each)" if m["mode"] == "accuracy"
            else "threaded runs (2 threads each)")
    load = p["load_1min"]
    lines = [f"### {m['title']}", "",
             f"Median (min-max) of each case's {m['runs']} {mode}. Command: `{command_of(m)}`.", "",
             f"Measured {p['first']}{'' if p['first'] == p['last'] else ' to ' + p['last']} on {'; '.join(p['machines']) or 'n/a'}; "
             f"load average (1 min) at the start of a run {cell(load, '{:.1f}')}; "
             f"crowdslam {', '.join(p['builds']) or 'n/a'}.", ""]
    has_ratio = any(c.get("ate_ratio") is not None for c in table["cases"].values())
    head = ["case", "runs"] + [t for _, t, _ in FIGURES] + (["ATE / baseline"] if has_ratio else [])
    lines += ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for name, c in table["cases"].items():
        row = [f"`{name}`", f"{c['complete']}/{m['runs']}"]
        row += [cell(c["stats"][k], f) for k, _, f in FIGURES]
        if has_ratio:
            row.append(fmt(c.get("ate_ratio"), "{:.1f}x"))
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "Case `DATASET.SETTINGS.OPTIONS`; arguments of each case:", ""]
    lines += [f"- `{name}`: `{' '.join(case['args'])}`" for name, case in m["cases"].items()]
    return "\n".join(lines) + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--matrix", required=True)
    p.add_argument("--results", required=True)
    p.add_argument("--out", required=True, help="output path without extension")
    a = p.parse_args()
    with open(a.matrix) as f:
        matrix = json.load(f)
    cases, all_runs = {}, []
    for name, case in matrix["cases"].items():
        runs = [r for r in map(run_figures, run_dirs(os.path.join(a.results, name))) if r is not None]
        all_runs += runs
        st = {k: stats([r["figures"][k] for r in runs]) for k, _, _ in FIGURES}
        st.update({k: stats([r["figures"][k] for r in runs]) for k in EXTRA})
        cases[name] = {"dataset": case["dataset"], "settings": case["settings"], "options": case["options"],
                       "label": case.get("label"), "complete": len(runs), "stats": st,
                       "runs": [dict(r["figures"], dir=os.path.relpath(r["dir"], a.results)) for r in runs]}
    for name, case in matrix["cases"].items():
        base = case.get("baseline")
        mine, theirs = cases[name]["stats"]["ate_m"]["median"], base and cases[base]["stats"]["ate_m"]["median"]
        cases[name]["ate_ratio"] = mine / theirs if mine is not None and theirs else None
    table = {"matrix": {k: v for k, v in matrix.items() if k != "detection"}, "cases": cases,
             "provenance": provenance(all_runs)}
    tmp = f"{a.out}.tmp-{os.getpid()}"
    with open(tmp + ".json", "w") as f:
        json.dump(table, f, indent=1)
    with open(tmp + ".md", "w") as f:
        f.write(markdown(table))
    with open(tmp + ".csv", "w", newline="") as f:
        w = csv.writer(f)
        keys = [k for k, _, _ in FIGURES] + EXTRA
        w.writerow(["case", "dataset", "settings", "options", "runs"] + [f"{k}_{s}" for k in keys for s in STATS] +
                   ["ate_ratio"])
        for name, c in cases.items():
            w.writerow([name, c["dataset"], c["settings"], c["options"], c["complete"]] +
                       ["" if c["stats"][k][s] is None else repr(c["stats"][k][s]) for k in keys for s in STATS] +
                       ["" if c["ate_ratio"] is None else repr(c["ate_ratio"])])
    for ext in ("csv", "md", "json"):
        os.replace(f"{tmp}.{ext}", f"{a.out}.{ext}")


if __name__ == "__main__":
    main()
