#pragma once
// The stereo rectification of a raw EuRoC pair, computed from its sensor.yaml calibrations (intrinsics,
// radial-tangential distortion, T_BS) with cv::stereoRectify: zero disparity at infinity, alpha 0 (only
// valid pixels), the same image size. The result has the LEFT/RIGHT blocks an ORB-SLAM2 EuRoC settings
// file would give; apply_rectification (settings.h) makes Camera.* describe the rectified left image.
#include <string>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/geometry/stereo_rectification.h"
#include "crowdslam/io/euroc_dataset.h"

namespace crowdslam::io {

// LEFT/RIGHT blocks for an EuRoC pair from its sensor.yaml calibrations. right_from_left maps points from
// the left (cam0) to the right (cam1) camera frame. Throws InputError (naming `source`) for a
// distortion model other than radial-tangential or cameras of different resolutions.
geometry::StereoRectification rectification_from_euroc(const EurocCameraCalibration& left,
                                                       const EurocCameraCalibration& right,
                                                       const geometry::Mat4& right_from_left,
                                                       const std::string& source);

}  // namespace crowdslam::io
