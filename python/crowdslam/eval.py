"""Trajectory accuracy, the same numbers as `crowdslam eval ate|rpe` (TUM benchmark metrics).

Trajectories are files (TUM, KITTI or EuRoC; the format is detected) or N x 8 float64 arrays of TUM rows
(timestamp tx ty tz qx qy qz qw), e.g. System.trajectory() or Sequence.ground_truth.
"""
from ._core import eval as _native

ate = _native.ate
rpe = _native.rpe
AteResult = _native.AteResult
RpeResult = _native.RpeResult
ErrorStats = _native.ErrorStats

__all__ = ["AteResult", "ErrorStats", "RpeResult", "ate", "rpe"]
