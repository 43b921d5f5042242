#!/usr/bin/python3
"""The table of a detection matrix: per configuration, precision / recall / MODA / MODP on each sequence
and pooled over all of them (true and false positives and misses summed), and the median detect() time
per frame (the median of the sequences' medians). Writes OUT.json, OUT.csv and OUT.md.

  aggregate_detect.py --matrix RESULTS/MATRIX/matrix.json --results RESULTS/MATRIX --out RESULTS/MATRIX/detect_table

Only complete results count: a detect directory with job.json (run_job.py) and its .eval.json.
"""
import argparse
import csv
import json
import os
import statistics

from aggregate import machine_name, stats, cell

METRICS = ("precision", "recall", "moda", "modp")


def pooled(evals):
    tp = sum(e["tp"] for e in evals)
    fp = sum(e["fp"] for e in evals)
    fn = sum(e["fn"] for e in evals)
    iou = sum((e["modp"] or 0) * e["tp"] for e in evals)
    n = tp + fn
    return {"precision": tp / (tp + fp) if tp + fp else None, "recall": tp / n if n else None,
            "moda": 1 - (fn + fp) / n if n else None, "modp": iou / tp if tp else None, "tp": tp, "fp": fp, "fn": fn}


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def pct(x):
    return "-" if x is None else f"{100 * x:.1f}"


def markdown(table):
    matrix, prov, rows = table["matrix"], table["provenance"], table["configs"]
    det = matrix["detection"]
    seqs = list(det["sequences"])
    files = matrix.get("configfiles") or [f"workflows/matrices/{matrix['matrix']}.yaml"]
    out = [f"### {matrix['title']}: person detection", "",
           f"Precision / recall / MODA / MODP in %, IoU {det['iou']}; ms/frame: median detect() time per frame "
           f"({det['threads']} OpenCV thread), the median of the sequences' medians. Command: "
           f"`snakemake -s workflows/Snakefile --configfile {' '.join(files)} --cores 2`.", "",
           f"Measured {prov['first']}{'' if prov['first'] == prov['last'] else ' to ' + str(prov['last'])} on "
           f"{'; '.join(prov['machines']) or 'n/a'}; load average (1 min) at the start of a job "
           f"{cell(prov['load_1min'], '{:.1f}')}.", ""]
    head = ["config"] + [f"{s} P / R / MODA / MODP" for s in seqs] + ["all P / R / MODA / MODP", "ms/frame"]
    out += ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for config, r in rows.items():
        cells = [" / ".join(pct(r["sequences"][s][k]) for k in METRICS) if s in r["sequences"] else "n/a"
                 for s in seqs]
        allm = " / ".join(pct(r["all"][k]) for k in METRICS) if r["all"] else "n/a"
        ms = "-" if r["ms_per_frame"] is None else f"{r['ms_per_frame']:.1f}"
        out.append(f"| `{config}` | " + " | ".join(cells) + f" | {allm} | {ms} |")
    out.append("")
    out += [f"- `{c}`: " + ("the sequence's published `det/det.txt`" if r["public"] else
                            f"`crowdslam detect {' '.join(r['args'])}`") for c, r in rows.items()]
    return "\n".join(out) + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--matrix", required=True)
    p.add_argument("--results", required=True)
    p.add_argument("--out", required=True)
    a = p.parse_args()
    matrix = load(a.matrix)
    det = matrix["detection"]
    seqs = list(det["sequences"])
    rows, machines, dates, loads = {}, set(), [], []
    for config, spec in det["configs"].items():
        per_seq, times = {}, []
        for seq in seqs:
            d = os.path.join(a.results, "detect", config, seq)
            job, ev = load(os.path.join(d, "job.json")), load(d + ".eval.json")
            if job is None or ev is None:
                continue
            per_seq[seq] = {k: ev[k] for k in METRICS + ("tp", "fp", "fn")}
            run = load(os.path.join(d, "detect.json"))
            if run:
                times.append(run["median_time_ms"])
                per_seq[seq]["detector"] = run.get("detector")
            machines.add(machine_name(job["machine"]))
            dates.append(job["started"][:10])
            if job.get("load_before"):
                loads.append(job["load_before"][0])
        rows[config] = {"args": spec["args"], "public": spec["public"], "sequences": per_seq,
                        "all": pooled(list(per_seq.values())) if per_seq else None,
                        "complete": len(per_seq), "ms_per_frame": statistics.median(times) if times else None}
    dates.sort()
    prov = {"machines": sorted(machines), "first": dates[0] if dates else None,
            "last": dates[-1] if dates else None, "load_1min": stats(loads)}
    table = {"matrix": {k: v for k, v in matrix.items() if k != "cases"}, "configs": rows, "provenance": prov}
    tmp = f"{a.out}.tmp-{os.getpid()}"
    with open(tmp + ".json", "w") as f:
        json.dump(table, f, indent=1)
    with open(tmp + ".csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["config", "sequence"] + list(METRICS) + ["tp", "fp", "fn", "ms_per_frame"])
        for config, r in rows.items():
            for seq, e in list(r["sequences"].items()) + ([("all", r["all"])] if r["all"] else []):
                w.writerow([config, seq] + ["" if e[k] is None else repr(e[k]) for k in METRICS] +
                           [e["tp"], e["fp"], e["fn"], "" if r["ms_per_frame"] is None else repr(r["ms_per_frame"])])
    with open(tmp + ".md", "w") as f:
        f.write(markdown(table))
    for ext in ("csv", "md", "json"):
        os.replace(f"{tmp}.{ext}", f"{a.out}.{ext}")


if __name__ == "__main__":
    main()
