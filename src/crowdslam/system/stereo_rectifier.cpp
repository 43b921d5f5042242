#include "crowdslam/system/stereo_rectifier.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/util/error.h"

namespace crowdslam::system {

namespace {
void build_maps(const io::RectificationSide& side, cv::Mat& map1, cv::Mat& map2) {
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

cv::Mat to_cv(const geometry::Mat3& m) {
  cv::Mat out(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.at<double>(r, c) = m(r, c);
  return out;
}

io::RectificationSide side_of(const io::EurocCameraCalibration& c, const std::string& source, const char* name) {
  if (!c.distortion_model.empty() && c.distortion_model != "radial-tangential" &&
      c.distortion_model != "radtan") {
    throw input_error(source, std::string(name) + ": distortion model '" + c.distortion_model +
                                  "' is not supported for rectification (radial-tangential only)");
  }
  if (c.distortion.size() != 4 && c.distortion.size() != 5) {
    throw input_error(source, std::string(name) + ": distortion_coefficients: expected 4 or 5 numbers, got " +
                                  std::to_string(c.distortion.size()));
  }
  io::RectificationSide s;
  s.width = c.width;
  s.height = c.height;
  s.K = (cv::Mat_<double>(3, 3) << c.intrinsics[0], 0, c.intrinsics[2], 0, c.intrinsics[1], c.intrinsics[3], 0,
         0, 1);
  s.D = cv::Mat(1, static_cast<int>(c.distortion.size()), CV_64F);
  for (size_t i = 0; i < c.distortion.size(); ++i) s.D.at<double>(0, static_cast<int>(i)) = c.distortion[i];
  return s;
}
}  // namespace

StereoRectifier::StereoRectifier(const io::StereoRectification& rectification, const std::string& source)
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

io::StereoRectification rectification_from_euroc(const io::EurocCameraCalibration& left,
                                                 const io::EurocCameraCalibration& right,
                                                 const geometry::Mat4& right_from_left, const std::string& source) {
  io::StereoRectification r;
  r.left = side_of(left, source, "cam0");
  r.right = side_of(right, source, "cam1");
  if (left.width != right.width || left.height != right.height) {
    throw input_error(source, "cam0 and cam1 resolutions differ (" + std::to_string(left.width) + "x" +
                                  std::to_string(left.height) + " vs " + std::to_string(right.width) + "x" +
                                  std::to_string(right.height) + ")");
  }
  const cv::Mat rotation = to_cv(right_from_left.topLeftCorner<3, 3>());
  const cv::Mat translation =
      (cv::Mat_<double>(3, 1) << right_from_left(0, 3), right_from_left(1, 3), right_from_left(2, 3));
  if (cv::norm(translation) <= 0) throw input_error(source, "cam0 and cam1 have no baseline (T_BS)");
  const cv::Size size(left.width, left.height);
  cv::Mat q;
  cv::stereoRectify(r.left.K, r.left.D, r.right.K, r.right.D, size, rotation, translation, r.left.R, r.right.R,
                    r.left.P, r.right.P, q, cv::CALIB_ZERO_DISPARITY, 0.0, size);
  // The baseline must come out along +x of the rectified left camera (right camera to the right).
  if (!(r.right.P.at<double>(0, 3) < 0)) {
    throw input_error(source, "cam1 is not to the right of cam0 after rectification (vertical or swapped pair)");
  }
  return r;
}

void apply_rectification(io::Settings& settings, const io::StereoRectification& rectification) {
  const cv::Mat& p = rectification.left.P;
  auto& c = settings.camera;
  c.fx = p.at<double>(0, 0);
  c.fy = p.at<double>(1, 1);
  c.cx = p.at<double>(0, 2);
  c.cy = p.at<double>(1, 2);
  c.k1 = c.k2 = c.p1 = c.p2 = c.k3 = 0.0;
  c.bf = -rectification.right.P.at<double>(0, 3);
  c.width = rectification.left.width;
  c.height = rectification.left.height;
  settings.rectification = rectification;
}

}  // namespace crowdslam::system
