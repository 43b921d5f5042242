#include <gtest/gtest.h>

#include <cmath>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/tum_dataset.h"
#include "crowdslam/util/error.h"
#include "test_dataset_helpers.h"

namespace crowdslam::io {
namespace {

using test::TempDir;
using test::write_text;

// Message of the InputError thrown by `f`, or "" when nothing is thrown.
using test::error_of;

TEST(TumDataset, AssociatesColourAndDepthWithinTwentyMilliseconds) {
  TempDir dir;
  // 0.066 is 0.021 s from its nearest depth stamp (0.045): left out. 0.2 has no colour partner.
  test::make_tum(dir.path(), {0.0, 0.033, 0.066}, {0.01, 0.045, 0.2});
  const auto dataset = open_dataset(dir.path().string());
  EXPECT_EQ(dataset->layout(), "tum");
  EXPECT_EQ(dataset->sensor(), SensorKind::kRgbd);
  ASSERT_EQ(dataset->size(), 2u);
  EXPECT_DOUBLE_EQ(dataset->frame_info(0).timestamp_s, 0.0);
  EXPECT_DOUBLE_EQ(dataset->frame_info(1).timestamp_s, 0.033);
  EXPECT_EQ(dataset->frame_info(1).depth_path, (dir / "depth/1.png").string());
  const auto summary = dataset->summary();
  EXPECT_EQ(summary.colour_entries, 3u);
  EXPECT_EQ(summary.depth_entries, 3u);
  EXPECT_EQ(summary.ground_truth_poses, 3u);
  EXPECT_DOUBLE_EQ(summary.last_timestamp_s, 0.033);

  const FrameImages images = dataset->load(1);
  EXPECT_EQ(images.colour.type(), CV_8UC3);
  EXPECT_EQ(images.colour.at<cv::Vec3b>(0, 0)[0], 1);  // rgb/1.png
  ASSERT_EQ(images.depth.type(), CV_16UC1);
  EXPECT_EQ(images.depth.at<uint16_t>(3, 3), 2000);  // depth/1.png, raw value kept
  EXPECT_TRUE(images.right.empty());
}

TEST(TumDataset, GroundTruthIsReadAsWorldFromCam) {
  TempDir dir;
  test::make_tum(dir.path(), {1.0, 2.0}, {1.0, 2.0}, false);
  // 90 degrees about z: qz = sin(45 deg), qw = cos(45 deg).
  write_text(dir / "groundtruth.txt",
             "# t tx ty tz qx qy qz qw\n1.5 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n");
  const auto dataset = open_dataset(dir.path().string());
  ASSERT_EQ(dataset->ground_truth().size(), 1u);
  const auto& pose = dataset->ground_truth()[0];
  EXPECT_DOUBLE_EQ(pose.timestamp_s, 1.5);
  const geometry::Vec3 x_in_world = pose.world_from_cam * geometry::Vec3(1, 0, 0);
  EXPECT_NEAR(x_in_world.x(), 1.0, 1e-12);
  EXPECT_NEAR(x_in_world.y(), 3.0, 1e-12);
  EXPECT_NEAR(x_in_world.z(), 3.0, 1e-12);
}

TEST(TumDataset, WithoutDepthListItIsMonocularOverEveryColourImage) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 0.5, 1.0}, {});
  const auto dataset = open_dataset(dir.path().string());
  EXPECT_EQ(dataset->sensor(), SensorKind::kMonocular);
  ASSERT_EQ(dataset->size(), 3u);
  EXPECT_TRUE(dataset->frame_info(2).depth_path.empty());
  // next() walks every frame in order, then ends.
  std::vector<int> seen;
  while (auto frame = dataset->next()) seen.push_back(frame->images.colour.at<cv::Vec3b>(0, 0)[0]);
  EXPECT_EQ(seen, (std::vector<int>{0, 1, 2}));
}

TEST(TumDataset, AcceptsAnyImageExtensionFromTheList) {
  TempDir dir;
  test::write_colour(dir / "rgb/a.jpg", 0);
  write_text(dir / "rgb.txt", "0.0 rgb/a.jpg\n");
  const auto dataset = open_dataset(dir.path().string());
  EXPECT_EQ(dataset->load(0).colour.size(), cv::Size(8, 6));
}

TEST(TumDatasetErrors, MissingDirectoryNamesIt) {
  const std::string path = "/nonexistent/crowdslam_dataset";
  EXPECT_NE(error_of([&] { (void)open_dataset(path); }).find(path), std::string::npos);
}

TEST(TumDatasetErrors, MissingColourListNamesIt) {
  TempDir dir;
  const auto message = error_of([&] { (void)open_tum_dataset(dir.path().string()); });
  EXPECT_NE(message.find("rgb.txt"), std::string::npos) << message;
}

TEST(TumDatasetErrors, EmptyListNamesIt) {
  TempDir dir;
  write_text(dir / "rgb.txt", "# only comments\n\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("rgb.txt"), std::string::npos) << message;
  EXPECT_NE(message.find("empty"), std::string::npos) << message;
}

TEST(TumDatasetErrors, ListLineWithTooFewFieldsNamesFileAndLine) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 1.0}, {0.0, 1.0});
  write_text(dir / "depth.txt", "# depth\n0.0 depth/0.png\n1.0\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("depth.txt:3:"), std::string::npos) << message;
}

TEST(TumDatasetErrors, NonNumericStampNamesFileAndLine) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {});
  write_text(dir / "rgb.txt", "abc rgb/0.png\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("rgb.txt:1:"), std::string::npos) << message;
  EXPECT_NE(message.find("abc"), std::string::npos) << message;
}

TEST(TumDatasetErrors, ListedImageThatIsMissingNamesListLineAndImage) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 1.0}, {0.0, 1.0});
  std::filesystem::remove(dir / "rgb/1.png");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("rgb.txt:4:"), std::string::npos) << message;
  EXPECT_NE(message.find("rgb/1.png"), std::string::npos) << message;
}

TEST(TumDatasetErrors, TruncatedPngIsRejectedOnLoad) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0, 1.0}, {0.0, 1.0});
  test::truncate_half(dir / "depth/1.png");
  const auto dataset = open_dataset(dir.path().string());
  EXPECT_NO_THROW((void)dataset->load(0));
  const auto message = error_of([&] { (void)dataset->load(1); });
  EXPECT_NE(message.find("depth/1.png"), std::string::npos) << message;
  EXPECT_NE(message.find("truncated"), std::string::npos) << message;
}

TEST(TumDatasetErrors, TruncatedJpegIsRejectedOnLoad) {
  TempDir dir;
  cv::Mat noise(120, 160, CV_8UC3);
  cv::randu(noise, 0, 255);  // noise makes a JPEG large enough that half of it still decodes
  std::filesystem::create_directories(dir / "rgb");
  cv::imwrite((dir / "rgb/0.jpg").string(), noise);
  test::truncate_half(dir / "rgb/0.jpg");
  write_text(dir / "rgb.txt", "0.0 rgb/0.jpg\n");
  const auto dataset = open_dataset(dir.path().string());
  const auto message = error_of([&] { (void)dataset->load(0); });
  EXPECT_NE(message.find("rgb/0.jpg"), std::string::npos) << message;
  EXPECT_NE(message.find("truncated JPEG"), std::string::npos) << message;
}

TEST(TumDatasetErrors, UndecodableImageNamesIt) {
  TempDir dir;
  write_text(dir / "rgb/0.png", "not an image at all");
  write_text(dir / "rgb.txt", "0.0 rgb/0.png\n");
  const auto dataset = open_dataset(dir.path().string());
  const auto message = error_of([&] { (void)dataset->load(0); });
  EXPECT_NE(message.find("rgb/0.png"), std::string::npos) << message;
}

TEST(TumDatasetErrors, EightBitDepthIsRejected) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {0.0});
  test::write_grey(dir / "depth/0.png", 7);
  const auto dataset = open_dataset(dir.path().string());
  const auto message = error_of([&] { (void)dataset->load(0); });
  EXPECT_NE(message.find("depth/0.png"), std::string::npos) << message;
  EXPECT_NE(message.find("16-bit"), std::string::npos) << message;
}

TEST(TumDatasetErrors, DepthOfAnotherSizeIsRejected) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {0.0});
  test::write_depth(dir / "depth/0.png", 5, {4, 3});
  const auto dataset = open_dataset(dir.path().string());
  const auto message = error_of([&] { (void)dataset->load(0); });
  EXPECT_NE(message.find("depth/0.png"), std::string::npos) << message;
  EXPECT_NE(message.find("4x3"), std::string::npos) << message;
}

TEST(TumDatasetErrors, GroundTruthWithNanNamesFileAndLine) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {0.0});
  write_text(dir / "groundtruth.txt", "# gt\n0.0 0 0 0 0 0 0 1\n0.1 nan 0 0 0 0 0 1\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("groundtruth.txt:3:"), std::string::npos) << message;
}

TEST(TumDatasetErrors, GroundTruthWithTooFewFieldsNamesFileAndLine) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {0.0});
  write_text(dir / "groundtruth.txt", "0.0 0 0 0 0 0 1\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("groundtruth.txt:1:"), std::string::npos) << message;
}

TEST(DatasetErrors, UnknownLayoutNamesTheDirectory) {
  TempDir dir;
  write_text(dir / "notes.txt", "nothing to see\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find(dir.path().string()), std::string::npos) << message;
  EXPECT_NE(message.find("unknown dataset layout"), std::string::npos) << message;
}

TEST(DatasetErrors, SettingsYamlInTheDirectoryIsTheDefault) {
  TempDir dir;
  test::make_tum(dir.path(), {0.0}, {0.0});
  EXPECT_EQ(open_dataset(dir.path().string())->default_settings_path(), "");
  write_text(dir / "settings.yaml", "%YAML:1.0\n");
  EXPECT_EQ(open_dataset(dir.path().string())->default_settings_path(), (dir / "settings.yaml").string());
}

}  // namespace
}  // namespace crowdslam::io
