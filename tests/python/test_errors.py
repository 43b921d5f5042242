"""Bad input: errors name the argument and what was expected; C++ InputErrors keep their message."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import crowdslam
from conftest import SOURCE_DIR, run_cli, vocabulary_available


@pytest.fixture(scope="module")
def slam(synth_settings: Path):
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as s:
        yield s


@pytest.fixture(scope="module")
def frame(synth_sequence: Path):
    return crowdslam.datasets.open(synth_sequence)[0]


def test_image_dtype_shape_and_type(slam, frame) -> None:
    depth = frame.depth
    with pytest.raises(TypeError, match=r"track\(\): image: expected uint8, shape \(H, W, 3\) BGR or \(H, W\) grey, "
                                        r"got float32 array of shape \(240, 320, 3\)"):
        slam.track(frame.image.astype(np.float32), depth, timestamp=0.0)
    with pytest.raises(ValueError, match=r"track\(\): image: expected uint8.*got uint8 array of shape \(240, 320, 4\)"):
        slam.track(np.zeros((240, 320, 4), np.uint8), depth, timestamp=0.0)
    with pytest.raises(TypeError, match=r"track\(\): image: expected a numpy array .*got list"):
        slam.track([[0, 1]], depth, timestamp=0.0)
    with pytest.raises(ValueError, match=r"track\(\): image: empty image of shape \(0, 320\)"):
        slam.track(np.zeros((0, 320), np.uint8), depth, timestamp=0.0)


def test_image_size_against_settings(slam, frame) -> None:
    with pytest.raises(ValueError, match=r"track\(\): image: 160x120 pixels, but the settings .*settings.yaml give "
                                         r"Camera.width/height 320x240"):
        slam.track(frame.image[:120, :160], frame.depth[:120, :160], timestamp=0.0)


def test_depth_errors(slam, frame) -> None:
    with pytest.raises(ValueError, match=r"track\(\): depth: the System's sensor is rgbd, which needs a depth image"):
        slam.track(frame.image, timestamp=0.0)
    with pytest.raises(TypeError, match=r"track\(\): depth: expected uint16 \(H, W\) raw sensor units or float32 "
                                        r"\(H, W\) metres, got int32 array"):
        slam.track(frame.image, frame.depth.astype(np.int32), timestamp=0.0)
    with pytest.raises(ValueError, match=r"track\(\): depth: 320x239 pixels, but the image is 320x240"):
        slam.track(frame.image, frame.depth[:239], timestamp=0.0)
    with pytest.raises(ValueError, match=r"track\(\): right: given, but the System's sensor is rgbd"):
        slam.track(frame.image, frame.depth, frame.image, timestamp=0.0)
    with pytest.raises(ValueError, match=r"track\(\): timestamp: expected a finite time"):
        slam.track(frame.image, frame.depth, timestamp=float("nan"))
    with pytest.raises(TypeError):  # timestamp is keyword-only and required
        slam.track(frame.image, frame.depth, None, 0.0)


def test_errors_leave_the_system_usable(synth_settings: Path, frame) -> None:
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as s:
        with pytest.raises(TypeError):
            s.track(frame.image.astype(np.int16), frame.depth, timestamp=0.0)
        result = s.track(frame.image, frame.depth, timestamp=frame.timestamp)
        assert result.index == 0 and result.state == "ok"  # RGB-D initialises on the first frame


def test_missing_settings_same_message_as_cli(tmp_path: Path, synth_sequence: Path) -> None:
    missing = tmp_path / "nope.yaml"
    with pytest.raises(crowdslam.InputError) as error:
        crowdslam.System(missing)
    cli = run_cli("run", "--dataset", str(synth_sequence), "--settings", str(missing), "--out", str(tmp_path / "o"),
                  check=False)
    assert cli.returncode != 0
    assert f"error: {error.value}" in cli.stderr
    assert str(missing) in str(error.value)
    assert isinstance(error.value, ValueError)


def test_invalid_setting_names_file_and_key(tmp_path: Path) -> None:
    text = (SOURCE_DIR / "config" / "Bonn.yaml").read_text().replace("Camera.fx:", "Camera.fx: -1 #", 1)
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    with pytest.raises(crowdslam.InputError, match=rf"{bad}: Camera.fx"):
        crowdslam.Settings.load(bad)


def test_bad_arguments(synth_settings: Path) -> None:
    with pytest.raises(crowdslam.InputError, match=r"System\(\): sensor: unknown sensor 'lidar'"):
        crowdslam.System(synth_settings, sensor="lidar")
    with pytest.raises(ValueError, match=r"System\(\): filter_mode: expected 'paper' or 'depth', got 'all'"):
        crowdslam.System(synth_settings, filter_mode="all")
    with pytest.raises(TypeError, match=r"System\(\): settings: expected a path .*got int"):
        crowdslam.System(42)
    with pytest.raises(crowdslam.InputError, match="nope.voc"):
        crowdslam.System(synth_settings, vocabulary="/nonexistent/nope.voc")
    with pytest.raises(crowdslam.InputError, match="no_such_dir"):
        crowdslam.datasets.open("/nonexistent/no_such_dir")


def test_closed_system_refuses_to_track(synth_settings: Path, frame) -> None:
    slam = crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none")
    slam.track(frame.image, frame.depth, timestamp=frame.timestamp)
    slam.close()
    assert slam.closed
    with pytest.raises(RuntimeError, match=r"System.track\(\): the System is closed"):
        slam.track(frame.image, frame.depth, timestamp=frame.timestamp + 1)
    slam.shutdown()  # idempotent
    assert slam.trajectory().shape == (1, 8)  # results stay readable
    with pytest.raises(RuntimeError, match=r"load_map\(\): the System is closed"):
        slam.load_map("whatever.db")


def test_timestamps_going_backwards_are_warned_about(synth_settings: Path, synth_sequence: Path) -> None:
    """Issue 37, finding 16: a frame whose timestamp is not after the previous one was taken silently."""
    frames = crowdslam.datasets.open(synth_sequence)
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as s:
        s.track(frames[1].image, frames[1].depth, timestamp=frames[1].timestamp)
        with pytest.warns(RuntimeWarning, match=r"track\(\): timestamp .* is not after the previous frame's"):
            s.track(frames[0].image, frames[0].depth, timestamp=frames[0].timestamp)


def test_corrupt_map_metadata_is_a_clear_error(synth_settings: Path, synth_sequence: Path, tmp_path: Path) -> None:
    """Issue 37, finding 12: 'abc' as the next keyframe id was ValueError('stoull')."""
    import sqlite3

    frames = crowdslam.datasets.open(synth_sequence)
    path = tmp_path / "m.db"
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as s:
        for f in [frames[i] for i in range(10)]:
            s.track(f.image, f.depth, timestamp=f.timestamp)
        s.save_map(str(path))
    with sqlite3.connect(path) as db:
        db.execute("UPDATE metadata SET value = 'abc' WHERE key = 'map.next_keyframe_id'")
    if not vocabulary_available():
        pytest.skip("loading a map needs the default vocabulary (scripts/setup.sh builds it)")
    with crowdslam.System(synth_settings, sequential=True, people_filter=False) as s:
        with pytest.raises(ValueError, match=r"m\.db: corrupt map: metadata map\.next_keyframe_id is not an id: abc"):
            s.load_map(str(path))


def test_save_map_never_replaces_what_is_not_a_map(synth_settings: Path, synth_sequence: Path, tmp_path: Path) -> None:
    """Issue 37, finding 1: save_map() renamed a map over whatever the path named."""
    frames = crowdslam.datasets.open(synth_sequence)
    other = tmp_path / "important.yaml"
    other.write_text("%YAML:1.0\n")
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as s:
        for i in range(5):
            s.track(frames[i].image, frames[i].depth, timestamp=frames[i].timestamp)
        with pytest.raises(ValueError, match=r"save_map\(\): path .*important\.yaml: exists and is not a crowdslam map"):
            s.save_map(str(other))
        s.save_map(str(tmp_path / "m.db"))
        s.save_map(str(tmp_path / "m.db"))  # a map may be replaced
    assert other.read_text() == "%YAML:1.0\n"
