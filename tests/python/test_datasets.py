"""crowdslam.datasets: iteration, random access, metadata, errors."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import crowdslam


def test_iteration_and_random_access(synth_sequence: Path) -> None:
    seq = crowdslam.datasets.open(synth_sequence)
    assert seq.layout == "tum" and seq.sensor == "rgbd" and seq.random_access
    assert seq.settings_path == str(synth_sequence / "settings.yaml")
    frames = list(seq)
    assert len(frames) == len(seq) == 60
    assert [f.index for f in frames] == list(range(60))
    rgb = [line.split() for line in (synth_sequence / "rgb.txt").read_text().splitlines() if not line.startswith("#")]
    assert [f.timestamp for f in frames] == [float(stamp) for stamp, _ in rgb]
    assert [Path(f.colour_path).name for f in frames] == [Path(name).name for _, name in rgb]
    for i in (0, 31, -1):
        assert np.array_equal(seq[i].image, frames[i].image)
        assert np.array_equal(seq[i].depth, frames[i].depth)
    assert frames[5].image.shape == (240, 320, 3) and frames[5].depth.dtype == np.uint16
    # A second pass starts again from the first frame.
    assert next(iter(seq)).index == 0
    with pytest.raises(IndexError, match="out of range"):
        seq[60]


def test_ground_truth_and_summary(synth_sequence: Path) -> None:
    seq = crowdslam.datasets.open(synth_sequence)
    gt = seq.ground_truth
    np.testing.assert_allclose(gt, np.loadtxt(synth_sequence / "groundtruth.txt"), atol=1e-9)
    summary = seq.summary()
    assert summary["frames"] == 60 and summary["ground_truth_poses"] == len(gt)


def test_stale_iterator(synth_sequence: Path) -> None:
    seq = crowdslam.datasets.open(synth_sequence)
    first = iter(seq)
    next(first)
    second = iter(seq)
    assert next(second).index == 0
    with pytest.raises(RuntimeError, match="stale"):
        next(first)


def test_errors_name_the_path(tmp_path: Path, synth_sequence: Path) -> None:
    with pytest.raises(crowdslam.InputError, match=str(tmp_path / "missing")):
        crowdslam.datasets.open(tmp_path / "missing")
    with pytest.raises(crowdslam.InputError, match="rgb.txt"):
        crowdslam.datasets.open(synth_sequence / "rgb.txt")  # a list file, not the dataset
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "rgb.txt").write_text("0.0 rgb/missing.png\n")
    (broken / "depth.txt").write_text("0.0 depth/missing.png\n")
    with pytest.raises(crowdslam.InputError, match="missing.png"):
        crowdslam.datasets.open(broken)
