"""crowdslam.Detector gives the boxes of `crowdslam detect` (the people filter's detector)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import crowdslam
from conftest import models_available, run_cli

pytestmark = pytest.mark.skipif(not models_available(), reason="person-detector models not installed")

FRAMES = 12


@pytest.mark.parametrize("raw", [False, True])
def test_boxes_equal_cli(synth_sequence: Path, tmp_path: Path, raw: bool) -> None:
    out = tmp_path / "det.txt"
    # The SLAM filter's detector (the settings' defaults), which crowdslam.Detector() builds; `detect`
    # without --settings defaults to a detection-quality setup instead, so it is named in full here.
    run_cli("--quiet", "detect", "--dataset", str(synth_sequence), "--out", str(out), "--max-frames", str(FRAMES),
            "--model", "body", "--input-size", "160", "--confidence", "0.2", "--nms", "0.1",
            *(["--raw"] if raw else []))
    rows = np.loadtxt(out, delimiter=",", ndmin=2)
    detector = crowdslam.Detector("body")
    assert "yolo-fastest" in detector.name.lower()
    seq = crowdslam.datasets.open(synth_sequence)
    total = 0
    for i in range(FRAMES):
        boxes, scores = detector.detect(seq[i].image, raw=raw)
        assert boxes.dtype == np.float32 and boxes.shape == (len(scores), 4)
        expected = rows[rows[:, 0] == i + 1] if len(rows) else np.zeros((0, 10))
        assert len(boxes) == len(expected), f"frame {i}"
        # The MOT file has 6 significant digits.
        np.testing.assert_allclose(boxes, expected[:, 2:6], rtol=1e-5, atol=1e-3)
        np.testing.assert_allclose(scores, expected[:, 6], rtol=1e-5, atol=1e-6)
        total += len(boxes)
    assert total > 0  # the synthetic sequence has people in view


def test_detect_errors() -> None:
    detector = crowdslam.Detector()
    with pytest.raises(TypeError, match=r"detect\(\): image: expected uint8.*got float64 array of shape \(4, 4\)"):
        detector.detect(np.zeros((4, 4)))
    with pytest.raises(crowdslam.InputError, match="nope.cfg"):
        crowdslam.Detector("/nonexistent/nope.cfg")
    with pytest.raises(crowdslam.InputError, match="confidence"):
        crowdslam.Detector(confidence=2.0)


def test_settings_model_by_name_equals_cli(synth_sequence: Path, tmp_path: Path) -> None:
    # A settings file naming a zoo model (Detector.model_cfg: yolox) with its own input and thresholds:
    # crowdslam.Detector(settings=...) resolves it as `crowdslam detect --settings` does.
    settings = tmp_path / "yolox.yaml"
    settings.write_text((synth_sequence / "settings.yaml").read_text() +
                        "\nDetector.model_cfg: yolox\nDetector.input_width: 256\nDetector.input_height: 192\n"
                        "Detector.confidence: 0.25\nDetector.nms: 0.4\nDetector.filter_before_nms: 0\n")
    out = tmp_path / "det.txt"
    run_cli("--quiet", "detect", "--dataset", str(synth_sequence), "--out", str(out), "--max-frames", str(FRAMES),
            "--settings", str(settings))
    rows = np.loadtxt(out, delimiter=",", ndmin=2)
    detector = crowdslam.Detector(settings=str(settings))
    assert "yolox" in detector.name.lower()
    seq = crowdslam.datasets.open(synth_sequence)
    total = 0
    for i in range(FRAMES):
        boxes, scores = detector.detect(seq[i].image)
        expected = rows[rows[:, 0] == i + 1] if len(rows) else np.zeros((0, 10))
        assert len(boxes) == len(expected), f"frame {i}"
        np.testing.assert_allclose(boxes, expected[:, 2:6], rtol=1e-5, atol=1e-3)
        np.testing.assert_allclose(scores, expected[:, 6], rtol=1e-5, atol=1e-6)
        total += len(boxes)
    assert total > 0
