// Dataset readers against the shared real data (skipped when ../shared is absent).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "crowdslam/io/associate.h"
#include "crowdslam/io/dataset.h"
#include "crowdslam/io/euroc_dataset.h"
#include "test_support.h"

namespace crowdslam::io {
namespace {

// Stamps of a TUM list, parsed here independently of the reader.
std::vector<double> list_stamps(const std::filesystem::path& list) {
  std::ifstream in(list);
  std::vector<double> stamps;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    stamps.push_back(std::stod(line.substr(0, line.find(' '))));
  }
  return stamps;
}

TEST(SharedBonn, CountsPairsAndGroundTruth) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const auto dir = test::shared_data("bonn_crowd");
  const auto dataset = open_dataset(dir.string());
  EXPECT_EQ(dataset->layout(), "tum");
  EXPECT_EQ(dataset->sensor(), SensorKind::kRgbd);
  const auto s = dataset->summary();
  EXPECT_EQ(s.colour_entries, 928u);  // README: 928 colour, 927 depth, 933 poses
  EXPECT_EQ(s.depth_entries, 927u);
  EXPECT_EQ(s.ground_truth_poses, 933u);
  const auto rgb = list_stamps(dir / "rgb.txt");
  const auto depth = list_stamps(dir / "depth.txt");
  EXPECT_EQ(dataset->size(), associate_timestamps(rgb, depth, 0.02).size());
  EXPECT_NEAR(s.last_timestamp_s - s.first_timestamp_s, 31.0, 0.5);  // README: 31 s at 30 Hz
  for (std::size_t i = 0; i < dataset->size(); ++i) {
    const auto& f = dataset->frame_info(i);
    const double depth_stamp = std::stod(std::filesystem::path(f.depth_path).stem().string());
    ASSERT_LT(std::abs(f.timestamp_s - depth_stamp), 0.02) << i;
    if (i > 0) {
      ASSERT_GT(f.timestamp_s, dataset->frame_info(i - 1).timestamp_s);
    }
  }
}

TEST(SharedBonn, FirstFrameIsColourAndSixteenBitDepthInMetresRange) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const auto dataset = open_dataset(test::shared_data("bonn_crowd").string());
  const auto images = dataset->load(0);
  EXPECT_EQ(images.colour.type(), CV_8UC3);
  EXPECT_EQ(images.colour.size(), cv::Size(640, 480));
  ASSERT_EQ(images.depth.type(), CV_16UC1);
  cv::Mat valid = images.depth > 0;
  const double mean_m = cv::mean(images.depth, valid)[0] / 5000.0;  // DepthMapFactor 5000
  EXPECT_GT(mean_m, 0.3);                                           // an indoor room seen by an Xtion
  EXPECT_LT(mean_m, 8.0);
  // First ground-truth line: 1548339819.89427 -0.194787 -1.44487 1.46988 0.163205 0.0885024 -0.227926
  // -0.955814
  const auto& gt = dataset->ground_truth().front();
  EXPECT_DOUBLE_EQ(gt.timestamp_s, 1548339819.89427);
  EXPECT_NEAR(gt.world_from_cam.translation().y(), -1.44487, 1e-12);
}

TEST(SharedEuroc, NinetyFiveStereoPairsAndEightyFourPoses) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  const auto dataset = open_dataset(test::shared_data("euroc_v101_micro").string());
  EXPECT_EQ(dataset->layout(), "euroc");
  EXPECT_EQ(dataset->sensor(), SensorKind::kStereo);
  EXPECT_EQ(dataset->size(), 95u);
  EXPECT_EQ(dataset->ground_truth().size(), 84u);
  // First row of cam0/data.csv: 1403715273262142976 ns; 20 Hz.
  EXPECT_NEAR(dataset->frame_info(0).timestamp_s, 1403715273.262142976, 1e-6);
  EXPECT_NEAR(dataset->frame_info(94).timestamp_s - dataset->frame_info(0).timestamp_s, 94 / 20.0, 1e-3);
  const auto images = dataset->load(0);
  EXPECT_EQ(images.colour.type(), CV_8UC1);
  EXPECT_EQ(images.colour.size(), cv::Size(752, 480));
  EXPECT_EQ(images.right.size(), cv::Size(752, 480));
}

TEST(SharedEuroc, CalibrationFromSensorYaml) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  const auto dataset = open_euroc_dataset(test::shared_data("euroc_v101_micro").string());
  const auto& left = dataset->left_calibration();
  EXPECT_DOUBLE_EQ(left.intrinsics[0], 458.654);
  EXPECT_DOUBLE_EQ(left.intrinsics[3], 248.375);
  ASSERT_EQ(left.distortion.size(), 4u);
  EXPECT_DOUBLE_EQ(left.distortion[0], -0.28340811);
  EXPECT_EQ(left.width, 752);
  EXPECT_DOUBLE_EQ(left.body_from_sensor(1, 3), -0.064676986768);
  // The right camera sits about 11 cm to the left camera's +x (EuRoC VI-sensor baseline).
  const auto right_from_left = dataset->right_from_left();
  ASSERT_TRUE(right_from_left.has_value());
  const Eigen::Vector3d left_in_right = right_from_left->topRightCorner<3, 1>();
  EXPECT_NEAR(left_in_right.norm(), 0.110, 0.002);
  EXPECT_LT(left_in_right.x(), -0.10);
}

}  // namespace
}  // namespace crowdslam::io
