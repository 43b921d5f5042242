#!/usr/bin/python3
"""The crowd matrix of docs/CROWDS.md: synthetic crowds (profile x density x seed) against the same
sequence with the people hidden (`synth --hide-people`, the empty-room baseline), on each sensor, with
each detector (the generator's boxes `gt`, the default `body`, `yolox`). Each case is run N times
threaded; the table gives medians of tracked %, map resets, bridged frames, ATE, the ATE over the empty
room's, and frames/s.

  scripts/crowd_matrix.py --out OUT [--profiles passing,standing] [--people 8,16] [--seeds 5]
                          [--sensors rgbd,stereo,mono] [--detectors gt,body] [--runs 5] [--frames 300]
                          [--set 'KEY: VALUE' ...]

--set appends a settings line to each sequence's settings.yaml (a copy in OUT/settings/), for the crowd
runs and the empty-room runs alike: an ablation of one setting.

Writes OUT/matrix.json (every run's figures) and OUT/matrix.md (the table); sequences are kept in
OUT/seq/ and reused when they exist. Needs the person sprites (scripts/build_people_sprites.sh).
CROWDSLAM_CLI names another crowdslam binary (default: build/apps/crowdslam/crowdslam).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLI = os.environ.get("CROWDSLAM_CLI", os.path.join(REPO, "build", "apps", "crowdslam", "crowdslam"))


def synth(out, profile, people, seed, frames, stereo, hidden):
    name = f"{profile}_{people}_s{seed}" + ("_stereo" if stereo else "") + ("_empty" if hidden else "")
    path = os.path.join(out, "seq", name)
    if not os.path.exists(os.path.join(path, "synth.json")):
        cmd = [CLI, "-q", "synth", "--out", path, "--force", "--frames", str(frames), "--people", str(people),
               "--crowd", profile, "--seed", str(seed)]
        if stereo:
            cmd.append("--stereo")
        if hidden:
            cmd.append("--hide-people")
        subprocess.run(cmd, check=True)
    return path


def settings_for(out, seq, extra):
    if not extra:
        return []
    os.makedirs(os.path.join(out, "settings"), exist_ok=True)
    path = os.path.join(out, "settings", os.path.basename(seq) + ".yaml")
    with open(os.path.join(seq, "settings.yaml")) as f:
        text = f.read()
    with open(path, "w") as f:
        f.write(text.rstrip("\n") + "\n" + "".join(line + "\n" for line in extra))
    return ["--settings", path]


def run_once(seq, out_dir, sensor, detector, empty, settings=()):
    cmd = [CLI, "-q", "--json", "run", "--dataset", seq, "--out", out_dir, "--overwrite", "--allow-untracked"]
    cmd += list(settings)
    if sensor == "mono":
        cmd += ["--sensor", "mono"]
    if empty:
        cmd.append("--no-people-filter")
    elif detector == "gt":
        cmd += ["--detections", os.path.join(seq, "people_gt.txt")]
    elif detector != "body":
        cmd += ["--detector", detector]
    subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out_dir, "run.json")) as f:
        doc = json.load(f)
    s = doc["summary"]
    return {"tracked_percent": s["tracked_percent"], "map_resets": s["map_resets"],
            "reanchors": s.get("reanchors", 0),
            "bridged": s.get("bridged_frames", 0), "ate_m": s["ate_rmse_m"], "fps": s["throughput_fps"],
            "end_state": doc["end_state"]}


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True)
    p.add_argument("--profiles", default="passing,standing")
    p.add_argument("--people", default="8,16")
    p.add_argument("--seeds", default="5")
    p.add_argument("--sensors", default="rgbd,stereo,mono")
    p.add_argument("--detectors", default="gt,body")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--frames", type=int, default=300)
    p.add_argument("--set", action="append", default=[], metavar="'KEY: VALUE'")
    a = p.parse_args()
    if not os.access(CLI, os.X_OK):
        sys.exit(f"crowd_matrix: {CLI} not built (scripts/setup.sh)")
    results = []
    rows = []
    for profile in a.profiles.split(","):
        for people in [int(x) for x in a.people.split(",")]:
            for seed in [int(x) for x in a.seeds.split(",")]:
                for sensor in a.sensors.split(","):
                    stereo = sensor == "stereo"
                    seq = synth(a.out, profile, people, seed, a.frames, stereo, False)
                    empty_seq = synth(a.out, profile, people, seed, a.frames, stereo, True)
                    base = f"{profile}_{people}_s{seed}_{sensor}"
                    empty = [run_once(empty_seq, os.path.join(a.out, "runs", f"{base}_empty_{k}"), sensor, None, True,
                                      settings_for(a.out, empty_seq, a.set))
                             for k in range(a.runs)]
                    empty_ate = median([r["ate_m"] for r in empty])
                    for detector in a.detectors.split(","):
                        runs = [run_once(seq, os.path.join(a.out, "runs", f"{base}_{detector}_{k}"), sensor,
                                         detector, False, settings_for(a.out, seq, a.set)) for k in range(a.runs)]
                        ate = median([r["ate_m"] for r in runs])
                        row = {"profile": profile, "people": people, "seed": seed, "sensor": sensor,
                               "detector": detector, "runs": runs, "empty_runs": empty,
                               "tracked_percent": median([r["tracked_percent"] for r in runs]),
                               "map_resets": median([r["map_resets"] for r in runs]),
                               "reanchors": median([r["reanchors"] for r in runs]),
                               "bridged": median([r["bridged"] for r in runs]),
                               "ate_m": ate, "empty_ate_m": empty_ate,
                               "ate_ratio": ate / empty_ate if ate is not None and empty_ate else None,
                               "fps": median([r["fps"] for r in runs])}
                        results.append(row)
                        fmt = lambda v, f: "-" if v is None else f.format(v)
                        rows.append(f"| {profile} | {people} | {seed} | {sensor} | {detector} | "
                                    f"{fmt(row['tracked_percent'], '{:.1f} %')} | {fmt(row['map_resets'], '{:g}')} | "
                                    f"{fmt(row['reanchors'], '{:g}')} | "
                                    f"{fmt(row['bridged'], '{:g}')} | {fmt(ate, '{:.4f}')} | {fmt(empty_ate, '{:.4f}')} | "
                                    f"{fmt(row['ate_ratio'], '{:.1f}x')} | {fmt(row['fps'], '{:.1f}')} |")
                        print(rows[-1], flush=True)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "matrix.json"), "w") as f:
        json.dump(results, f, indent=1)
    header = ["| profile | people | seed | sensor | detector | tracked | map resets | re-anchorings | bridged | "
              "ATE (m) | empty room ATE (m) | ratio | frames/s |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    with open(os.path.join(a.out, "matrix.md"), "w") as f:
        f.write(f"Medians of {a.runs} threaded runs each, {a.frames} frames; command: "
                f"`scripts/crowd_matrix.py {' '.join(sys.argv[1:])}`\n\n")
        f.write("\n".join(header + rows) + "\n")


if __name__ == "__main__":
    main()
