import os
from typing import Union

import numpy as np
import numpy.typing as npt

TrajectoryLike = Union[str, "os.PathLike[str]", npt.NDArray[np.float64]]

class ErrorStats:
    count: int
    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float
    def as_dict(self) -> dict[str, float]: ...

class AteResult:
    translation_error: ErrorStats  # metres
    ground_truth_poses: int
    estimate_poses: int
    @property
    def rmse(self) -> float: ...
    @property
    def compared_pose_pairs(self) -> int: ...
    @property
    def errors(self) -> npt.NDArray[np.float64]: ...
    @property
    def rotation(self) -> npt.NDArray[np.float64]: ...  # 3 x 3
    @property
    def translation(self) -> npt.NDArray[np.float64]: ...  # 3
    @property
    def scale(self) -> float: ...

class RpeResult:
    translation_error: ErrorStats  # metres
    rotation_error: ErrorStats  # degrees
    ground_truth_max_time_difference: float
    @property
    def rmse(self) -> float: ...
    @property
    def compared_pose_pairs(self) -> int: ...

def ate(
    ground_truth: TrajectoryLike,
    estimate: TrajectoryLike,
    align: str = "se3",
    max_diff: float = 0.02,
    offset: float = 0.0,
    scale: float = 1.0,
) -> AteResult: ...
def rpe(
    ground_truth: TrajectoryLike,
    estimate: TrajectoryLike,
    delta: float = 1.0,
    delta_unit: str = "s",
    offset: float = 0.0,
    scale: float = 1.0,
) -> RpeResult: ...
