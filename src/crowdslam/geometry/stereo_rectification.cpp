#include "crowdslam/geometry/stereo_rectification.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/util/error.h"

namespace crowdslam::geometry {

namespace {
void build_maps(const RectificationSide& side, cv::Mat& map1, cv::Mat& map2) {
  // Fixed-point maps (CV_16SC2 + interpolation table): remap is about twice as fast as with float maps.
  cv::initUndistortRectifyMap(side.K, side.D, side.R, side.P(cv::Rect(0, 0, 3, 3)),
                              cv::Size(side.width, side.height), CV_16SC2, map1, map2);
}

void remap_checked(const cv::Mat& raw, cv::Mat& rectified, const cv::Mat& map1, const cv::Mat& map2,
                   cv::Size expected, const std::string& source, const char* side) {
  if (raw.size() != expected) {
    throw input_error(source, std::string(side) + ": image is " + std::to_string(raw.cols) + "x" +
                                  std::to_string(raw.rows) + " but the rectification is for " +
                                  std::to_string(expected.width) + "x" + std::to_string(expected.height) +
                                  " (" + side + ".width/height)");
  }
  cv::remap(raw, rectified, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
}

}  // namespace

StereoRectifier::StereoRectifier(const StereoRectification& rectification, const std::string& source)
    : source_(source),
      left_size_(rectification.left.width, rectification.left.height),
      right_size_(rectification.right.width, rectification.right.height) {
  if (left_size_ != right_size_) {
    throw input_error(source, "LEFT.width/height and RIGHT.width/height differ: the rectified images must have one size");
  }
  build_maps(rectification.left, left_map1_, left_map2_);
  build_maps(rectification.right, right_map1_, right_map2_);
}

void StereoRectifier::rectify_left(const cv::Mat& raw, cv::Mat& rectified) const {
  remap_checked(raw, rectified, left_map1_, left_map2_, left_size_, source_, "LEFT");
}

void StereoRectifier::rectify_right(const cv::Mat& raw, cv::Mat& rectified) const {
  remap_checked(raw, rectified, right_map1_, right_map2_, right_size_, source_, "RIGHT");
}

}  // namespace crowdslam::geometry
