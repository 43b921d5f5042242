#pragma once
// Rectification of raw stereo pairs (EuRoC) before feature extraction.
//
// The rectification comes from a settings file's LEFT/RIGHT blocks (K, D, R, P per camera, ORB-SLAM2
// EuRoC style) or is computed from the EuRoC sensor.yaml calibration (intrinsics, radial-tangential
// distortion, T_BS) with cv::stereoRectify (zero disparity at infinity, alpha 0: only valid pixels, same
// image size). Either way Camera.* of the settings describe the rectified left image: fx, fy, cx, cy =
// LEFT.P, bf = -RIGHT.P(0,3), no distortion. Pre-rectified pairs (KITTI, our synthetic sequences) have no
// LEFT/RIGHT blocks and are used as they are.
#include <string>

#include <opencv2/core.hpp>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/io/euroc_dataset.h"
#include "crowdslam/io/settings.h"

namespace crowdslam::system {

class StereoRectifier {
 public:
  // Precomputes the remap tables. `source` names where the rectification came from, for error messages.
  StereoRectifier(const io::StereoRectification& rectification, const std::string& source);

  // Rectified images (bilinear). Throws InputError when an image's size is not LEFT/RIGHT.width x height.
  void rectify_left(const cv::Mat& raw, cv::Mat& rectified) const;
  void rectify_right(const cv::Mat& raw, cv::Mat& rectified) const;

  [[nodiscard]] cv::Size left_size() const { return left_size_; }
  [[nodiscard]] cv::Size right_size() const { return right_size_; }

 private:
  std::string source_;
  cv::Size left_size_;
  cv::Size right_size_;
  cv::Mat left_map1_, left_map2_;
  cv::Mat right_map1_, right_map2_;
};

// LEFT/RIGHT blocks for an EuRoC pair from its sensor.yaml calibrations. right_from_left maps points from
// the left (cam0) to the right (cam1) camera frame. Throws InputError (naming `source`) for a
// distortion model other than radial-tangential or cameras of different resolutions.
io::StereoRectification rectification_from_euroc(const io::EurocCameraCalibration& left,
                                                 const io::EurocCameraCalibration& right,
                                                 const geometry::Mat4& right_from_left, const std::string& source);

// Sets settings.rectification and Camera.* (fx, fy, cx, cy from LEFT.P, bf = -RIGHT.P(0,3), distortion
// zero, width and height of the rectified images).
void apply_rectification(io::Settings& settings, const io::StereoRectification& rectification);

}  // namespace crowdslam::system
