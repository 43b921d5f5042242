#include "crowdslam/io/euroc_rectification.h"

#include <opencv2/calib3d.hpp>

#include "crowdslam/util/error.h"

namespace crowdslam::io {

namespace {
cv::Mat to_cv(const geometry::Mat3& m) {
  cv::Mat out(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.at<double>(r, c) = m(r, c);
  return out;
}

geometry::RectificationSide side_of(const EurocCameraCalibration& c, const std::string& source, const char* name) {
  if (!c.distortion_model.empty() && c.distortion_model != "radial-tangential" &&
      c.distortion_model != "radtan") {
    throw input_error(source, std::string(name) + ": distortion model '" + c.distortion_model +
                                  "' is not supported for rectification (radial-tangential only)");
  }
  if (c.distortion.size() != 4 && c.distortion.size() != 5) {
    throw input_error(source, std::string(name) + ": distortion_coefficients: expected 4 or 5 numbers, got " +
                                  std::to_string(c.distortion.size()));
  }
  geometry::RectificationSide s;
  s.width = c.width;
  s.height = c.height;
  s.K = (cv::Mat_<double>(3, 3) << c.intrinsics[0], 0, c.intrinsics[2], 0, c.intrinsics[1], c.intrinsics[3], 0,
         0, 1);
  s.D = cv::Mat(1, static_cast<int>(c.distortion.size()), CV_64F);
  for (size_t i = 0; i < c.distortion.size(); ++i) s.D.at<double>(0, static_cast<int>(i)) = c.distortion[i];
  return s;
}
}  // namespace

geometry::StereoRectification rectification_from_euroc(const EurocCameraCalibration& left,
                                                       const EurocCameraCalibration& right,
                                                       const geometry::Mat4& right_from_left,
                                                       const std::string& source) {
  geometry::StereoRectification r;
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

}  // namespace crowdslam::io
