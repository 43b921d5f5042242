"""Threads: track() releases the GIL, and reading the map from another thread while tracking is safe.

scripts/sanitize.sh thread runs this file against a TSan build of the module (docs/PYTHON.md).
"""
from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import numpy as np

import crowdslam

FRAMES = int(os.environ.get("CROWDSLAM_PYTEST_THREAD_FRAMES", "40"))


def load_frames(synth_sequence: Path, n: int):
    seq = crowdslam.datasets.open(synth_sequence)
    return [seq[i] for i in range(n)]


def test_map_reader_thread_while_tracking(synth_sequence: Path, synth_settings: Path) -> None:
    frames = load_frames(synth_sequence, FRAMES)
    boxes = str(synth_sequence / "people_gt.txt")
    # Reference: the same frames, sequential mode, no second thread.
    with crowdslam.System(synth_settings, sequential=True, detections=boxes) as alone:
        for f in frames:
            alone.track(f.image, f.depth, timestamp=f.timestamp)

    slam = crowdslam.System(synth_settings, sequential=True, detections=boxes)
    done = threading.Event()
    reads: list[int] = []
    errors: list[BaseException] = []

    def reader() -> None:
        try:
            while not done.is_set():
                points = slam.map_points()
                assert points.positions.shape == (len(points.ids), 3)
                assert np.isfinite(points.positions).all()
                slam.keyframes()
                reads.append(len(points.ids))
        except BaseException as e:  # noqa: BLE001 (reported by the main thread)
            errors.append(e)

    thread = threading.Thread(target=reader)
    thread.start()
    try:
        for f in frames:
            slam.track(f.image, f.depth, timestamp=f.timestamp)
            # Let the reader read at least once per frame: on loaded cores the tracking loop could otherwise
            # end before the reader is scheduled at all. Its reads still overlap the next track() call.
            before = len(reads)
            deadline = time.monotonic() + 10.0
            while len(reads) == before and not errors and thread.is_alive() and time.monotonic() < deadline:
                time.sleep(0.001)
    finally:
        done.set()
        thread.join()
    slam.close()
    assert not errors, errors
    assert len(reads) >= FRAMES and max(reads) > 0  # the reader really ran during tracking
    # Reading the map does not change what is tracked.
    np.testing.assert_array_equal(slam.trajectory(), alone.trajectory())


def test_threaded_mode_with_a_reader_thread(synth_sequence: Path, synth_settings: Path) -> None:
    # Threaded: local mapping and loop closing in their own threads, the map read from a Python thread.
    frames = load_frames(synth_sequence, FRAMES)
    with crowdslam.System(synth_settings, detections=str(synth_sequence / "people_gt.txt")) as slam:
        done = threading.Event()
        counts: list[int] = []
        thread = threading.Thread(target=lambda: [counts.append(len(slam.map_points().ids)) for _ in iter(done.is_set, True)])
        thread.start()
        for f in frames:
            slam.track(f.image, f.depth, timestamp=f.timestamp)
        done.set()
        thread.join()
    assert len(counts) > 0
    assert slam.stats()["tracked_frames"] == FRAMES


def test_track_releases_the_gil(synth_sequence: Path, synth_settings: Path) -> None:
    frames = load_frames(synth_sequence, 10)
    ticks: list[float] = []
    stop = threading.Event()

    def ticker() -> None:  # pure Python: runs only while no other thread holds the GIL
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.0005)

    calls: list[tuple[float, float]] = []
    with crowdslam.System(synth_settings, sequential=True, people_filter=False, vocabulary="none") as slam:
        thread = threading.Thread(target=ticker)
        thread.start()
        for f in frames:
            start = time.perf_counter()
            slam.track(f.image, f.depth, timestamp=f.timestamp)
            calls.append((start, time.perf_counter()))
        stop.set()
        thread.join()
    inside = sum(1 for t in ticks for a, b in calls if a < t < b)
    assert inside > len(calls), f"{inside} ticks of the other thread inside {len(calls)} track() calls"
