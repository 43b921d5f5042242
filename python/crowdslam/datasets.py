"""Datasets, videos and cameras as `crowdslam run --dataset` reads them (README "Input layouts").

    seq = crowdslam.datasets.open("../shared/data/bonn_crowd")   # TUM/Bonn, EuRoC, KITTI, images, video, "0"
    for frame in seq:                     # decoded ahead on a thread, as the CLI does
        frame.image, frame.depth, frame.right, frame.timestamp
    seq.ground_truth                      # N x 8 TUM array (empty when the dataset has none)
"""
from ._core import datasets as _native

open = _native.open  # noqa: A001 (crowdslam.datasets.open, like io.open)
Sequence = _native.Sequence
Frame = _native.Frame
FrameIterator = _native.FrameIterator

__all__ = ["Frame", "FrameIterator", "Sequence", "open"]
