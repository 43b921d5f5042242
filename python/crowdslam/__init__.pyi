# Type stubs of the crowdslam package (the native part is crowdslam._core; see docs/PYTHON.md).
import os
from types import TracebackType
from typing import NamedTuple, Optional, Union

import numpy as np
import numpy.typing as npt

from . import datasets as datasets
from . import eval as eval

__version__: str
__git_commit__: str
PathLike = Union[str, "os.PathLike[str]"]

class InputError(ValueError):
    """A file, setting or argument is wrong; the message names it (the CLI's one-line error)."""

def set_log_level(level: str) -> None: ...

class CameraSettings:
    fx: float
    fy: float
    cx: float
    cy: float
    k1: float
    k2: float
    p1: float
    p2: float
    k3: float
    width: int
    height: int
    bf: float
    fps: float
    rgb: bool

class OrbSettings:
    n_features: int
    scale_factor: float
    n_levels: int
    ini_th_fast: int
    min_th_fast: int

class DetectorSettings:
    model_cfg: str
    model_weights: str
    input_size: int
    confidence: float
    nms: float
    person_class: int
    filter_before_nms: Optional[bool]  # None: raw boxes with a depth camera, NMS boxes stereo and monocular

class PeopleFilterSettings:
    enabled: bool
    mode: str
    margin_px: float
    depth_margin_m: float
    right_image: str

class FeatureBudgetSettings:
    enabled: bool
    thresholds: list[float]
    factors: list[float]
    area: str

class OutputSettings:
    trajectory_format: str

class Settings:
    path: str
    camera: CameraSettings
    th_depth: float
    depth_map_factor: float
    orb: OrbSettings
    detector: DetectorSettings
    people_filter: PeopleFilterSettings
    feature_budget: FeatureBudgetSettings
    output: OutputSettings
    @property
    def has_rectification(self) -> bool: ...
    def __init__(self) -> None: ...
    @staticmethod
    def load(path: PathLike, sensor: str = "rgbd") -> Settings: ...
    def save(self, path: PathLike) -> None: ...
    def check(self, sensor: str = "rgbd") -> None: ...

class FrameResult:
    @property
    def index(self) -> int: ...
    @property
    def timestamp(self) -> float: ...
    @property
    def state(self) -> str: ...  # "ok", "lost", "not_initialized"
    @property
    def ok(self) -> bool: ...
    @property
    def method(self) -> str: ...
    @property
    def pose(self) -> Optional[npt.NDArray[np.float64]]: ...  # 4 x 4 world_from_cam
    @property
    def tracked_points(self) -> int: ...
    @property
    def keypoints(self) -> int: ...
    @property
    def keypoints_before_filter(self) -> int: ...
    @property
    def keypoints_removed(self) -> int: ...
    @property
    def is_keyframe(self) -> bool: ...
    @property
    def feature_budget(self) -> int: ...
    @property
    def person_boxes(self) -> npt.NDArray[np.float32]: ...  # N x 4: x, y, width, height
    @property
    def person_scores(self) -> npt.NDArray[np.float32]: ...
    @property
    def num_people(self) -> int: ...
    @property
    def people_area(self) -> float: ...
    @property
    def kept_keypoints(self) -> npt.NDArray[np.float32]: ...  # N x 2
    @property
    def removed_keypoints(self) -> npt.NDArray[np.float32]: ...
    @property
    def timings(self) -> dict[str, float]: ...

class MapPoints(NamedTuple):
    positions: npt.NDArray[np.float32]
    observations: npt.NDArray[np.int32]
    ids: npt.NDArray[np.uint64]

class Keyframes(NamedTuple):
    ids: npt.NDArray[np.uint64]
    timestamps: npt.NDArray[np.float64]
    poses: npt.NDArray[np.float64]

class System:
    def __init__(
        self,
        settings: Union[PathLike, Settings],
        sensor: str = "rgbd",
        vocabulary: Optional[str] = None,
        people_filter: bool = True,
        detector: Optional[str] = None,
        detections: Optional[str] = None,
        sequential: bool = False,
        loop_closing: bool = True,
        filter_mode: Optional[str] = None,
        record_keypoints: bool = False,
        max_wait_for_mapping_ms: float = 1000.0,
        replay_waits_for_mapping: bool = True,
    ) -> None: ...
    def __enter__(self) -> System: ...
    def __exit__(
        self,
        exc_type: Optional[type[BaseException]],
        exc: Optional[BaseException],
        traceback: Optional[TracebackType],
    ) -> None: ...
    def track(
        self,
        image: npt.NDArray[np.uint8],
        depth: Optional[Union[npt.NDArray[np.uint16], npt.NDArray[np.float32]]] = None,
        right: Optional[npt.NDArray[np.uint8]] = None,
        *,
        timestamp: float,
    ) -> FrameResult: ...
    def shutdown(self) -> None: ...
    def close(self) -> None: ...
    @property
    def closed(self) -> bool: ...
    @property
    def sensor(self) -> str: ...
    @property
    def sequential(self) -> bool: ...
    @property
    def settings(self) -> Settings: ...
    def trajectory(self) -> npt.NDArray[np.float64]: ...  # N x 8 TUM rows
    def keyframe_trajectory(self) -> npt.NDArray[np.float64]: ...
    def save_trajectory(self, path: str, format: str = "", keyframes: bool = False) -> None: ...
    def map_points(self) -> MapPoints: ...
    def keyframes(self) -> Keyframes: ...
    def load_map(self, path: str, localization: bool = False) -> dict[str, object]: ...
    def save_map(self, path: str, dataset: str = "") -> None: ...
    def stats(self) -> dict[str, object]: ...

class Detector:
    def __init__(
        self,
        model: Optional[str] = None,
        *,
        settings: Optional[str] = None,
        input_size: Optional[int] = None,
        confidence: Optional[float] = None,
        nms: Optional[float] = None,
        person_class: Optional[int] = None,
    ) -> None: ...
    def detect(
        self, image: npt.NDArray[np.uint8], raw: bool = False
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
    @property
    def name(self) -> str: ...
    @property
    def last_time_ms(self) -> float: ...
