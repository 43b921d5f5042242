#!/usr/bin/env python3
"""A dataset to a TUM trajectory and its ATE, from Python (what `crowdslam run` does, in 30 lines).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/run_dataset.py \
        ../shared/data/bonn_crowd --settings config/Bonn.yaml --out /tmp/bonn.txt
"""
import argparse
import time

import crowdslam

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("dataset", help="dataset directory (TUM/Bonn, EuRoC, KITTI, images) or video")
parser.add_argument("--settings", help="settings file (default: DATASET/settings.yaml)")
parser.add_argument("--sensor", help="rgbd, stereo or mono (default: the dataset's)")
parser.add_argument("--out", default="CameraTrajectory.txt", help="TUM trajectory to write")
parser.add_argument("--sequential", action="store_true", help="reproducible: mapping inline after each frame")
parser.add_argument("--no-people-filter", action="store_true")
args = parser.parse_args()

seq = crowdslam.datasets.open(args.dataset)
sensor = args.sensor or seq.sensor
with crowdslam.System(args.settings or seq.settings_path, sensor=sensor, sequential=args.sequential,
                      people_filter=not args.no_people_filter) as slam:
    start = time.perf_counter()
    for n, frame in enumerate(seq, 1):
        slam.track(frame.image, frame.depth if sensor == "rgbd" else None,
                   frame.right if sensor == "stereo" else None, timestamp=frame.timestamp)
    seconds = time.perf_counter() - start
slam.save_trajectory(args.out, format="tum")
print(f"{n} frames in {seconds:.1f} s ({n / seconds:.2f} frames/s), {slam.stats()['tracked_frames']} tracked -> {args.out}")
if len(seq.ground_truth):
    ate = crowdslam.eval.ate(seq.ground_truth, slam.trajectory(), align="sim3" if sensor.startswith("mono") else "se3")
    print(f"ATE RMSE {ate.rmse:.4f} m over {ate.compared_pose_pairs} poses")
