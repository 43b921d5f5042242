// Stereo rectification: computed from EuRoC-style calibration (closed-form check with projected 3D
// points), against the shipped config/EuRoC.yaml, remap tables, and its errors.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>

#include "crowdslam/io/euroc_dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/geometry/stereo_rectification.h"
#include "crowdslam/io/euroc_rectification.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

using namespace crowdslam;

namespace {
io::EurocCameraCalibration camera(double fu, double fv, double cu, double cv, std::vector<double> distortion) {
  io::EurocCameraCalibration c;
  c.intrinsics = {fu, fv, cu, cv};
  c.distortion_model = "radial-tangential";
  c.distortion = std::move(distortion);
  c.width = 752;
  c.height = 480;
  return c;
}

// Pixel of a point (camera frame) in a raw camera with radial-tangential distortion.
cv::Point2d project_raw(const io::EurocCameraCalibration& c, const Eigen::Vector3d& p) {
  const cv::Mat k = (cv::Mat_<double>(3, 3) << c.intrinsics[0], 0, c.intrinsics[2], 0, c.intrinsics[1],
                     c.intrinsics[3], 0, 0, 1);
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Point3d>{{p.x(), p.y(), p.z()}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k,
                    c.distortion, out);
  return out[0];
}

// Rectified pixel of a raw pixel (what the remap tables invert).
cv::Point2d rectify_point(const geometry::RectificationSide& s, const cv::Point2d& raw) {
  std::vector<cv::Point2d> out;
  cv::undistortPoints(std::vector<cv::Point2d>{raw}, out, s.K, s.D, s.R, s.P);
  return out[0];
}
}  // namespace

TEST(StereoRectifier, RectifiedPairHasEqualRowsAndDisparityBfOverDepth) {
  // Right camera 11 cm to the right, slightly rotated and offset: rows differ before rectification.
  const auto left = camera(458.0, 457.0, 367.0, 248.0, {-0.28, 0.07, 0.0002, 0.00002});
  const auto right = camera(457.5, 456.0, 380.0, 255.0, {-0.283, 0.074, -0.0001, -0.00003});
  Eigen::Matrix4d right_from_left = Eigen::Matrix4d::Identity();
  right_from_left.topLeftCorner<3, 3>() =
      (Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.005, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  right_from_left.topRightCorner<3, 1>() = Eigen::Vector3d(-0.11, 0.001, 0.0005);
  const geometry::StereoRectification r = io::rectification_from_euroc(left, right, right_from_left, "test");

  io::Settings settings;
  io::apply_rectification(settings, r);
  const double baseline = right_from_left.topRightCorner<3, 1>().norm();
  EXPECT_NEAR(settings.camera.bf, settings.camera.fx * baseline, 1e-9 * settings.camera.bf);
  EXPECT_EQ(settings.camera.k1, 0.0);
  EXPECT_EQ(settings.camera.width, 752);

  // Points at known positions project to the same rectified row in both images, with disparity bf / z'
  // (z' = depth in the rectified left camera).
  const Eigen::Matrix3d rect_left = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.left.R.ptr<double>());
  int checked = 0;
  for (double x : {-1.0, 0.0, 0.7}) {
    for (double y : {-0.5, 0.2}) {
      for (double z : {1.5, 4.0, 9.0}) {
        const Eigen::Vector3d p_left(x * z / 3, y * z / 3, z);
        const Eigen::Vector3d p_right = (right_from_left * p_left.homogeneous()).head<3>();
        const cv::Point2d l = rectify_point(r.left, project_raw(left, p_left));
        const cv::Point2d rr = rectify_point(r.right, project_raw(right, p_right));
        const double depth = (rect_left * p_left).z();
        EXPECT_NEAR(l.y, rr.y, 1e-3);
        EXPECT_NEAR(l.x - rr.x, settings.camera.bf / depth, 1e-3);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 18);
}

TEST(StereoRectifier, EurocCalibrationGivesTheShippedSettings) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  const auto dataset = io::open_euroc_dataset(test::shared_data("euroc_v101_micro").string());
  ASSERT_TRUE(dataset->right_calibration().has_value());
  const auto computed = io::rectification_from_euroc(dataset->left_calibration(), *dataset->right_calibration(),
                                                         *dataset->right_from_left(), "euroc");
  const io::Settings shipped =
      io::load_settings((test::source_dir() / "config" / "EuRoC.yaml").string(), io::SensorKind::kStereo);
  ASSERT_TRUE(shipped.rectification.has_value());
  EXPECT_LT(cv::norm(computed.left.P, shipped.rectification->left.P, cv::NORM_INF), 1e-6);
  EXPECT_LT(cv::norm(computed.right.P, shipped.rectification->right.P, cv::NORM_INF), 1e-6);
  EXPECT_LT(cv::norm(computed.left.R, shipped.rectification->left.R, cv::NORM_INF), 1e-9);
  EXPECT_LT(cv::norm(computed.right.R, shipped.rectification->right.R, cv::NORM_INF), 1e-9);
}

TEST(StereoRectifier, IdentityRectificationLeavesTheImageAndChecksItsSize) {
  geometry::RectificationSide side;
  side.width = 64;
  side.height = 48;
  side.K = (cv::Mat_<double>(3, 3) << 50, 0, 32, 0, 50, 24, 0, 0, 1);
  side.D = cv::Mat::zeros(1, 4, CV_64F);
  side.R = cv::Mat::eye(3, 3, CV_64F);
  side.P = cv::Mat::zeros(3, 4, CV_64F);
  side.K.copyTo(side.P(cv::Rect(0, 0, 3, 3)));
  const geometry::StereoRectifier rectifier({side, side}, "settings.yaml");
  cv::Mat image(48, 64, CV_8UC1);
  cv::randu(image, 0, 256);
  cv::Mat out;
  rectifier.rectify_left(image, out);
  EXPECT_EQ(cv::norm(image, out, cv::NORM_INF), 0.0);

  const std::string error = test::error_of([&] { rectifier.rectify_right(cv::Mat(40, 64, CV_8UC1), out); });
  EXPECT_NE(error.find("settings.yaml"), std::string::npos) << error;
  EXPECT_NE(error.find("RIGHT"), std::string::npos) << error;
}

TEST(StereoRectifier, UnsupportedCalibrationIsAnError) {
  auto left = camera(458, 457, 367, 248, {0.1, 0.0, 0.0, 0.0});
  auto right = left;
  Eigen::Matrix4d right_from_left = Eigen::Matrix4d::Identity();
  right_from_left(0, 3) = -0.1;
  right.distortion_model = "equidistant";
  EXPECT_NE(test::error_of([&] { io::rectification_from_euroc(left, right, right_from_left, "x"); })
                .find("equidistant"),
            std::string::npos);
  right = left;
  right_from_left(0, 3) = 0.0;
  EXPECT_NE(test::error_of([&] { io::rectification_from_euroc(left, right, right_from_left, "x"); })
                .find("baseline"),
            std::string::npos);
  right_from_left(0, 3) = 0.1;  // right camera on the left
  EXPECT_NE(test::error_of([&] { io::rectification_from_euroc(left, right, right_from_left, "x"); })
                .find("right of cam0"),
            std::string::npos);
}
