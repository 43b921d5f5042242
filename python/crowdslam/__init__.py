"""crowdslam: visual SLAM for crowded places, as a library (docs/PYTHON.md).

    import crowdslam
    seq = crowdslam.datasets.open("../shared/data/bonn_crowd")
    with crowdslam.System("config/Bonn.yaml", sensor="rgbd") as slam:
        for frame in seq:
            result = slam.track(frame.image, frame.depth, timestamp=frame.timestamp)
    print(crowdslam.eval.ate(seq.ground_truth, slam.trajectory()).rmse)
"""
from __future__ import annotations

import atexit
from typing import NamedTuple

import numpy as np

from . import _core
from ._core import Detector, FrameResult, InputError, Settings, __git_commit__, __version__, set_log_level
from . import datasets, eval  # noqa: A004 (crowdslam.eval, as `crowdslam eval`)

__all__ = [
    "Detector", "FrameResult", "InputError", "Keyframes", "MapPoints", "Settings", "System", "datasets", "eval",
    "set_log_level", "__version__", "__git_commit__",
]


class MapPoints(NamedTuple):
    """The map's points (System.map_points())."""

    positions: np.ndarray  # N x 3 float32, world frame, metres (arbitrary scale for monocular)
    observations: np.ndarray  # N int32: how many keyframes observe each point
    ids: np.ndarray  # N uint64


class Keyframes(NamedTuple):
    """The map's keyframes (System.keyframes())."""

    ids: np.ndarray  # N uint64
    timestamps: np.ndarray  # N float64 seconds
    poses: np.ndarray  # N x 4 x 4 float64 world_from_cam


class System(_core.System):
    __doc__ = _core.System.__doc__

    def map_points(self) -> MapPoints:
        """A consistent copy of the current map's points (taken under the map lock; safe while another
        thread tracks: it waits for the frame being tracked)."""
        return MapPoints(*self._map_points())

    def keyframes(self) -> Keyframes:
        """A consistent copy of the current map's keyframes."""
        return Keyframes(*self._keyframes())

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        mode = "sequential" if self.sequential else "threaded"
        return f"<crowdslam.System {self.sensor} {mode} {state}>"


# The SLAM threads must not outlive the interpreter: an open System left in a global (or in a thread
# that is still tracking) is stopped here, before Python tears its objects down.
atexit.register(_core._stop_all)
