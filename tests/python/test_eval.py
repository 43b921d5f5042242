"""crowdslam.eval gives the numbers of `crowdslam eval`, on files and on arrays."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import crowdslam
from conftest import cli_json


def rotation_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def quaternion_z(angle: float) -> np.ndarray:  # x y z w
    return np.array([0, 0, np.sin(angle / 2), np.cos(angle / 2)])


@pytest.fixture(scope="module")
def estimate(synth_sequence: Path, tmp_path_factory) -> Path:
    """The ground truth moved, rotated, scaled and perturbed: an estimate with a known error structure."""
    gt = np.loadtxt(synth_sequence / "groundtruth.txt")
    rng = np.random.default_rng(3)
    est = gt.copy()
    est[:, 1:4] = 0.8 * gt[:, 1:4] @ rotation_z(0.3).T + [0.5, -0.2, 0.1] + rng.normal(0, 0.01, (len(gt), 3))
    est = est[::2]  # every other pose, so the association matters
    path = tmp_path_factory.mktemp("eval") / "estimate.txt"
    np.savetxt(path, est, fmt="%.9f")
    return path


def ground_truth(synth_sequence: Path) -> Path:
    return synth_sequence / "groundtruth.txt"


@pytest.mark.parametrize("align", ["se3", "sim3", "none"])
def test_ate_equals_cli_on_files_and_arrays(synth_sequence: Path, estimate: Path, align: str) -> None:
    gt = ground_truth(synth_sequence)
    cli = cli_json("eval", "ate", str(gt), str(estimate), "--align", align)
    for result in (crowdslam.eval.ate(str(gt), str(estimate), align=align),
                   crowdslam.eval.ate(np.loadtxt(gt), np.loadtxt(estimate), align=align),
                   crowdslam.eval.ate(gt, estimate, align=align)):  # pathlib.Path
        stats = cli["absolute_translational_error_m"]
        for key in ("rmse", "mean", "median", "std", "min", "max"):
            assert getattr(result.translation_error, key) == pytest.approx(stats[key], abs=1e-9, rel=0)
        assert result.compared_pose_pairs == cli["compared_pose_pairs"]
        assert result.scale == pytest.approx(cli["transform"]["scale"], abs=1e-9)
        np.testing.assert_allclose(result.rotation, cli["transform"]["rotation"], atol=1e-9, rtol=0)
        np.testing.assert_allclose(result.translation, cli["transform"]["translation"], atol=1e-9, rtol=0)
        assert result.errors.shape == (result.compared_pose_pairs,)
        assert np.sqrt(np.mean(result.errors**2)) == pytest.approx(result.rmse, abs=1e-12)


@pytest.mark.parametrize("delta,unit", [(1.0, "s"), (5, "frames")])
def test_rpe_equals_cli(synth_sequence: Path, estimate: Path, delta: float, unit: str) -> None:
    gt = ground_truth(synth_sequence)
    cli = cli_json("eval", "rpe", str(gt), str(estimate), "--delta", str(delta), "--delta-unit", unit)
    for result in (crowdslam.eval.rpe(str(gt), str(estimate), delta=delta, delta_unit=unit),
                   crowdslam.eval.rpe(np.loadtxt(gt), np.loadtxt(estimate), delta=delta, delta_unit=unit)):
        assert result.compared_pose_pairs == cli["compared_pose_pairs"] > 0
        for ours, key in ((result.translation_error, "translational_error_m"), (result.rotation_error, "rotational_error_deg")):
            for stat in ("rmse", "mean", "median", "std", "min", "max"):
                assert getattr(ours, stat) == pytest.approx(cli[key][stat], abs=1e-9, rel=0)


def test_ate_closed_form() -> None:
    # A straight line, the estimate shifted by a constant: no alignment -> every error is the shift.
    stamps = np.arange(20) / 10.0
    gt = np.zeros((20, 8))
    gt[:, 0] = stamps
    gt[:, 1] = stamps
    gt[:, 2] = np.sin(stamps)
    gt[:, 7] = 1.0
    est = gt.copy()
    est[:, 1:4] += [0.3, 0.4, 0.0]
    result = crowdslam.eval.ate(gt, est, align="none")
    assert result.rmse == pytest.approx(0.5, abs=1e-12)
    assert result.translation_error.std == pytest.approx(0.0, abs=1e-12)
    # SE3 alignment removes a rigid motion exactly.
    est[:, 1:4] = gt[:, 1:4] @ rotation_z(1.0).T + [1, 2, 3]
    est[:, 4:8] = quaternion_z(1.0)
    assert crowdslam.eval.ate(gt, est).rmse == pytest.approx(0.0, abs=1e-9)
    # RPE of a rigidly moved trajectory is zero too.
    assert crowdslam.eval.rpe(gt, est, delta=3, delta_unit="frames").rmse == pytest.approx(0.0, abs=1e-9)


def test_eval_errors_name_the_argument(synth_sequence: Path, tmp_path: Path) -> None:
    gt = np.loadtxt(ground_truth(synth_sequence))
    with pytest.raises(ValueError, match=r"ate\(\): estimate: expected .*shape \(N, 8\).*got float64 array of shape \(5, 7\)"):
        crowdslam.eval.ate(gt, np.zeros((5, 7)))
    with pytest.raises(TypeError, match=r"ate\(\): ground_truth: expected a trajectory file path or an N x 8"):
        crowdslam.eval.ate([1, 2, 3], gt)
    bad = gt.copy()
    bad[4, 4:8] = 0
    with pytest.raises(ValueError, match=r"row 4: zero quaternion"):
        crowdslam.eval.ate(gt, bad)
    missing = tmp_path / "missing.txt"
    with pytest.raises(crowdslam.InputError, match=str(missing)):
        crowdslam.eval.ate(str(missing), gt)
    with pytest.raises(crowdslam.InputError, match="alignment"):
        crowdslam.eval.ate(gt, gt, align="affine")
