"""System from Python: results, map access, input layouts, saved maps."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import crowdslam
from conftest import run_cli, vocabulary_available

FRAMES = 30


def run(settings: Path, frames, convert=lambda f: (f.image, f.depth), **options) -> crowdslam.System:
    slam = crowdslam.System(settings, sequential=True, people_filter=False, **options)
    with slam:
        for frame in frames:
            image, depth = convert(frame)
            slam.track(image, depth, timestamp=frame.timestamp)
    return slam


@pytest.fixture(scope="module")
def frames(synth_sequence: Path):
    seq = crowdslam.datasets.open(synth_sequence)
    return [seq[i] for i in range(FRAMES)]


@pytest.fixture(scope="module")
def reference(synth_settings: Path, frames) -> crowdslam.System:
    return run(synth_settings, frames, vocabulary="none")


def test_results_and_map(reference: crowdslam.System, frames) -> None:
    trajectory = reference.trajectory()
    assert trajectory.shape == (FRAMES, 8) and trajectory.dtype == np.float64
    assert np.array_equal(trajectory[:, 0], [f.timestamp for f in frames])
    np.testing.assert_allclose(np.linalg.norm(trajectory[:, 4:8], axis=1), 1.0, atol=1e-12)
    points = reference.map_points()
    assert points.positions.dtype == np.float32 and points.positions.shape == (len(points.ids), 3)
    assert len(points.ids) == reference.stats()["map_points"] > 100
    assert points.observations.min() >= 1
    keyframes = reference.keyframes()
    assert keyframes.poses.shape == (len(keyframes.ids), 4, 4)
    # keyframe_trajectory() is the keyframes' poses, as TUM rows.
    kf_rows = reference.keyframe_trajectory()
    np.testing.assert_allclose(kf_rows[:, 1:4], keyframes.poses[:, :3, 3], atol=1e-12)
    np.testing.assert_array_equal(kf_rows[:, 0], keyframes.timestamps)
    # The first keyframe is the first frame, at the origin (RGB-D initialisation).
    np.testing.assert_allclose(keyframes.poses[0], np.eye(4), atol=1e-12)


def test_frame_result_pose_is_world_from_cam(synth_settings: Path, frames) -> None:
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as slam:
        results = [slam.track(f.image, f.depth, timestamp=f.timestamp) for f in frames[:5]]
        trajectory = slam.trajectory()
    assert results[0].pose is not None and np.allclose(results[0].pose, np.eye(4))
    last = results[-1].pose
    assert last.shape == (4, 4) and np.allclose(last[3], [0, 0, 0, 1])
    np.testing.assert_allclose(last[:3, :3] @ last[:3, :3].T, np.eye(3), atol=1e-9)
    # Without later bundle adjustment moving it much, the tracking-time pose is the trajectory's last row.
    np.testing.assert_allclose(last[:3, 3], trajectory[-1, 1:4], atol=1e-3)
    assert results[0].timings["total_ms"] >= results[0].timings["tracking_ms"] >= 0


def test_float32_metres_depth_equals_uint16(synth_settings: Path, frames, reference) -> None:
    factor = crowdslam.Settings.load(synth_settings).depth_map_factor
    slam = run(synth_settings, frames, lambda f: (f.image, f.depth.astype(np.float32) / np.float32(factor)),
               vocabulary="none")
    np.testing.assert_array_equal(slam.trajectory(), reference.trajectory())


def test_non_contiguous_arrays_equal_contiguous(synth_settings: Path, frames, reference) -> None:
    def views(f):
        # A Fortran-ordered copy and a strided view of a wider buffer: layouts copied or described as is.
        wide = np.zeros((f.image.shape[0], f.image.shape[1] + 8, 3), np.uint8)
        wide[:, 4:-4] = f.image
        return wide[:, 4:-4], np.asfortranarray(f.depth)
    slam = run(synth_settings, frames, views, vocabulary="none")
    np.testing.assert_array_equal(slam.trajectory(), reference.trajectory())


def test_grey_images(synth_settings: Path, frames) -> None:
    def grey(f):  # the luma the system computes itself (BT.601, as cv::cvtColor)
        weights = np.array([0.114, 0.587, 0.299])
        return np.round(f.image @ weights).astype(np.uint8), f.depth
    slam = run(synth_settings, frames[:10], grey, vocabulary="none")
    assert slam.stats()["tracked_frames"] == 10


def test_dataset_images_are_not_copied(frames) -> None:
    image = frames[0].image
    assert image.dtype == np.uint8 and image.shape == (240, 320, 3)
    # Two reads of the same frame's property share the buffer the C++ frame owns.
    assert np.shares_memory(frames[0].image, frames[0].image)
    assert frames[0].depth.dtype == np.uint16


@pytest.mark.skipif(not vocabulary_available(), reason="default vocabulary not built (scripts/build_vocabulary.sh)")
def test_save_and_load_map(synth_settings: Path, frames, tmp_path: Path) -> None:
    slam = run(synth_settings, frames)
    path = tmp_path / "map.db"
    slam.save_map(str(path), dataset="synthetic")
    info = run_cli("--json", "map", "info", str(path)).stdout
    assert f'"keyframes": {slam.stats()["keyframes"]}' in info
    with crowdslam.System(synth_settings, sequential=True, people_filter=False) as again:
        loaded = again.load_map(str(path), localization=True)
        assert loaded["keyframes"] == slam.stats()["keyframes"]
        assert loaded["origin"]["dataset"] == "synthetic"
        result = again.track(frames[10].image, frames[10].depth, timestamp=frames[10].timestamp)
        assert result.state == "ok"  # relocalised in the loaded map
        assert again.stats()["keyframes"] == loaded["keyframes"]  # localisation only: no new keyframe


def test_save_map_needs_shutdown_in_threaded_mode(synth_settings: Path, frames, tmp_path: Path) -> None:
    slam = crowdslam.System(synth_settings, people_filter=False, vocabulary="none")
    slam.track(frames[0].image, frames[0].depth, timestamp=frames[0].timestamp)
    with pytest.raises(RuntimeError, match=r"call shutdown\(\) first"):
        slam.save_map(str(tmp_path / "m.db"))
    slam.close()


def test_settings_round_trip(synth_settings: Path, tmp_path: Path) -> None:
    settings = crowdslam.Settings.load(synth_settings)
    assert settings.camera.width == 320 and settings.camera.height == 240
    assert settings.path == str(synth_settings)
    settings.orb.n_features = 700
    settings.save(tmp_path / "s.yaml")
    again = crowdslam.Settings.load(tmp_path / "s.yaml")
    assert again == settings and again.orb.n_features == 700
    with crowdslam.System(again, sequential=True, people_filter=False, vocabulary="none") as slam:
        assert slam.settings.orb.n_features == 700
