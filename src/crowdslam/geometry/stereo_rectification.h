#pragma once
// Rectification of raw stereo pairs (EuRoC) before feature extraction.
//
// The rectification (io::Settings::rectification) comes from a settings file's LEFT/RIGHT blocks (K, D, R, P per camera, ORB-SLAM2
// EuRoC style) or is computed from the EuRoC sensor.yaml calibration (intrinsics, radial-tangential
// distortion, T_BS) with cv::stereoRectify (zero disparity at infinity, alpha 0: only valid pixels, same
// image size). Either way Camera.* of the settings describe the rectified left image: fx, fy, cx, cy =
// LEFT.P, bf = -RIGHT.P(0,3), no distortion. Pre-rectified pairs (KITTI, our synthetic sequences) have no
// LEFT/RIGHT blocks and are used as they are.
#include <string>

#include <opencv2/core.hpp>

namespace crowdslam::geometry {

// One camera of a stereo rectification (ORB-SLAM2's LEFT/RIGHT settings blocks): the raw camera's K and D,
// the rectifying rotation R and the rectified projection P.
struct RectificationSide {
  int width = 0;
  int height = 0;
  cv::Mat K;  // 3x3 CV_64F
  cv::Mat D;  // 1xN CV_64F (4, 5, 8, 12 or 14 coefficients)
  cv::Mat R;  // 3x3 CV_64F
  cv::Mat P;  // 3x4 CV_64F
};

struct StereoRectification {
  RectificationSide left;
  RectificationSide right;
};

class StereoRectifier {
 public:
  // Precomputes the remap tables. `source` names where the rectification came from, for error messages.
  StereoRectifier(const StereoRectification& rectification, const std::string& source);

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

}  // namespace crowdslam::geometry
