"""`crowdslam map optimise` and scripts/map_vs_groundtruth.py on a synthetic RGB-D map (docs/MAPPING.md
"How to measure"). They live with the pytest files because the checks edit map files with Python's sqlite3.

The synthetic sequence is rendered from known camera poses, so the map's observations must agree with its
ground truth, and a global bundle adjustment must pull perturbed keyframes back to where the measurements
put them.
"""
from __future__ import annotations

import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import SOURCE_DIR, cli_json, run_cli

SCRIPT = SOURCE_DIR / "scripts" / "map_vs_groundtruth.py"


@pytest.fixture(scope="module")
def saved_map(synth_sequence: Path, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("map")
    run_cli("--quiet", "run", "--dataset", str(synth_sequence), "--out", str(out / "run"), "--sequential",
            "--no-people-filter", "--vocabulary", "none", "--save-map", str(out / "room.db"))
    return out / "room.db"


def keyframe_centres(path: Path) -> dict[int, np.ndarray]:
    db = sqlite3.connect(path)
    centres = {}
    for kid, qx, qy, qz, qw, tx, ty, tz in db.execute("SELECT id, qx, qy, qz, qw, tx, ty, tz FROM keyframes"):
        x, y, z, w = qx, qy, qz, qw
        r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        centres[kid] = -r.T @ np.array([tx, ty, tz])
    db.close()
    return centres


def test_optimise_pulls_perturbed_keyframes_back(saved_map: Path, tmp_path: Path) -> None:
    perturbed = tmp_path / "perturbed.db"
    shutil.copyfile(saved_map, perturbed)
    original = keyframe_centres(saved_map)
    assert len(original) >= 5
    first = min(original)
    db = sqlite3.connect(perturbed)
    with db:  # +-3 cm on every keyframe but the first (the optimisation's fixed gauge)
        db.execute("UPDATE keyframes SET tx = tx + 0.03 * ((id % 3) - 1), ty = ty - 0.03 * ((id % 2) * 2 - 1) "
                   "WHERE id != ?", (first,))
    db.close()
    moved = keyframe_centres(perturbed)
    before = np.mean([np.linalg.norm(moved[k] - original[k]) for k in original])
    assert before > 0.02

    optimised = tmp_path / "optimised.db"
    report = cli_json("map", "optimise", str(perturbed), "--out", str(optimised), "--iterations", "30")
    assert report["keyframes"] == len(original)
    assert report["after"]["observations"] == report["before"]["observations"]
    assert report["after"]["rms_px"] < 0.5 * report["before"]["rms_px"]
    assert report["final_cost"] < report["initial_cost"]
    result = keyframe_centres(optimised)
    after = np.mean([np.linalg.norm(result[k] - original[k]) for k in original])
    assert after < 0.15 * before, (before, after)
    # The input is untouched, and an existing output is not replaced without --overwrite.
    unchanged = keyframe_centres(perturbed)
    assert all(np.array_equal(unchanged[k], moved[k]) for k in moved)
    again = run_cli("map", "optimise", str(perturbed), "--out", str(optimised), check=False)
    assert again.returncode == 1 and "--overwrite" in again.stderr


def test_groundtruth_check_finds_the_synthetic_map_consistent(saved_map: Path, synth_sequence: Path,
                                                               tmp_path: Path) -> None:
    gt_map = tmp_path / "gt.db"
    result = subprocess.run([sys.executable, str(SCRIPT), str(saved_map), str(synth_sequence),
                             "--write-groundtruth-map", str(gt_map)], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    scale = float(next(l for l in lines if "Sim(3) scale" in l).split()[-1])
    assert scale == pytest.approx(1.0, abs=0.03)  # RGB-D: the map is metric
    rows = [l for l in lines if l.strip().endswith("%") and "deg" in l]
    assert rows, result.stdout
    for row in rows:  # no observation is a false match: none beyond 6 sigma under the true poses
        assert float(row.split()[-2]) == 0.0, row
    # The map with true poses: its keyframe centres are the ground truth's (in the map's frame).
    run_cli("map", "export", str(gt_map), "--trajectory", str(tmp_path / "gt.txt"))
    ate = cli_json("eval", "ate", str(synth_sequence / "groundtruth.txt"), str(tmp_path / "gt.txt"), "--align", "sim3")
    assert ate["compared_pose_pairs"] >= 5
    assert ate["absolute_translational_error_m"]["rmse"] < 1e-3
    # And the script refuses to overwrite it.
    again = subprocess.run([sys.executable, str(SCRIPT), str(saved_map), str(synth_sequence),
                            "--write-groundtruth-map", str(gt_map)], capture_output=True, text=True)
    assert again.returncode == 1 and "exists" in again.stderr


def test_groundtruth_check_errors_name_the_file(tmp_path: Path, synth_sequence: Path) -> None:
    missing = tmp_path / "absent.db"
    result = subprocess.run([sys.executable, str(SCRIPT), str(missing), str(synth_sequence)],
                            capture_output=True, text=True)
    assert result.returncode == 1 and str(missing) in result.stderr
    junk = tmp_path / "junk.db"
    junk.write_text("not a database")
    result = subprocess.run([sys.executable, str(SCRIPT), str(junk), str(synth_sequence)],
                            capture_output=True, text=True)
    assert result.returncode == 1 and "not a crowdslam map" in result.stderr
