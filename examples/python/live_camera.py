#!/usr/bin/env python3
"""A live camera (cv2.VideoCapture) into monocular SLAM, printing the tracking state; q or Ctrl-C stops.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/live_camera.py --settings my_camera.yaml

The settings file describes the camera (Camera.fx/fy/cx/cy/k1.., width/height, fps; see config/). crowdslam
can read a camera by itself too (`crowdslam.datasets.open(0)`); this example shows frames that come from
your own code, e.g. a robot's driver.
"""
import argparse
import sys
import time

try:
    import cv2
except ImportError:
    sys.exit("live_camera.py needs OpenCV's Python bindings: sudo apt-get install python3-opencv")

import crowdslam

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--settings", required=True, help="settings file of the camera")
parser.add_argument("--camera", type=int, default=0, help="camera index for cv2.VideoCapture")
parser.add_argument("--show", action="store_true", help="show the image with the person boxes")
args = parser.parse_args()

capture = cv2.VideoCapture(args.camera)
if not capture.isOpened():
    sys.exit(f"cannot open camera {args.camera}")
start = time.monotonic()
with crowdslam.System(args.settings, sensor="mono") as slam:
    try:
        while True:
            ok, image = capture.read()  # uint8 BGR (H, W, 3): passed to track() without a copy
            if not ok:
                break
            result = slam.track(image, timestamp=time.monotonic() - start)
            print(f"\rframe {result.index}: {result.state:15s} {result.tracked_points:4d} points, "
                  f"{result.num_people} people", end="", flush=True)
            if args.show:
                for x, y, w, h in result.person_boxes.astype(int):
                    cv2.rectangle(image, (x, y), (x + w, y + h), (0, 0, 255), 2)
                cv2.imshow("crowdslam", image)
                if cv2.waitKey(1) & 0xFF == ord("q"):
                    break
    except KeyboardInterrupt:
        pass
print(f"\n{slam.stats()['tracked_frames']} frames tracked, {len(slam.map_points().ids)} map points")
slam.save_trajectory("live_trajectory.txt", format="tum")
