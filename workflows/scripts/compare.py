#!/usr/bin/python3
"""One `crowdslam report --compare` page for a group of cases (the cases of one dataset, by default):
each case is shown by its median run (the run whose ATE is the median of the case's runs; the lower
middle one for an even count, the first run when there is no ATE).

  compare.py --table RESULTS/MATRIX/table.json --group NAME --bin CROWDSLAM --out PAGE.html
"""
import argparse
import json
import os
import subprocess
import sys


def median_run(runs):
    with_ate = sorted((r for r in runs if r.get("ate_m") is not None), key=lambda r: r["ate_m"])
    if with_ate:
        return with_ate[(len(with_ate) - 1) // 2]
    return runs[0] if runs else None


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--table", required=True)
    p.add_argument("--group", required=True)
    p.add_argument("--bin", required=True)
    p.add_argument("--out", required=True)
    a = p.parse_args()
    with open(a.table) as f:
        table = json.load(f)
    by = table["matrix"].get("compare_by", "dataset")
    root = os.path.dirname(os.path.abspath(a.table))
    dirs = []
    for name, case in table["cases"].items():
        if case[by] != a.group:
            continue
        run = median_run(case["runs"])
        if run is None:
            print(f"compare: {name} has no complete run; left out", file=sys.stderr)
            continue
        dirs.append(os.path.join(root, run["dir"]))
    if not dirs:
        sys.exit(f"compare: no complete run in group {a.group}")
    tmp = f"{a.out}.tmp-{os.getpid()}.html"
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    cmd = [a.bin, "-q", "report", dirs[0], "--out", tmp] + (["--compare"] + dirs[1:] if len(dirs) > 1 else [])
    r = subprocess.run(cmd)
    if r.returncode != 0:
        if os.path.exists(tmp):
            os.unlink(tmp)
        sys.exit(f"compare: {' '.join(cmd)} failed (exit {r.returncode})")
    os.replace(tmp, a.out)


if __name__ == "__main__":
    main()
