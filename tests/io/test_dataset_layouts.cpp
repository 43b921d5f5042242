// KITTI, EuRoC, image folder and video sources on hand-made data.
#include <gtest/gtest.h>

#include <opencv2/videoio.hpp>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/euroc_dataset.h"
#include "crowdslam/io/kitti_dataset.h"
#include "crowdslam/util/error.h"
#include "test_dataset_helpers.h"

namespace crowdslam::io {
namespace {

using test::TempDir;
using test::write_text;

using test::error_of;

const char* kKittiCalib =
    "P0: 700 0 600 0 0 710 180 0 0 0 1 0\n"
    "P1: 700 0 600 -378 0 710 180 0 0 0 1 0\n";

void make_kitti(const std::filesystem::path& dir, int frames, bool stereo) {
  char name[16];
  std::string times;
  for (int i = 0; i < frames; ++i) {
    std::snprintf(name, sizeof(name), "%06d.png", i);
    test::write_grey(dir / "image_0" / name, i);
    if (stereo) test::write_grey(dir / "image_1" / name, 100 + i);
    times += std::to_string(0.1 * i) + "\n";
  }
  write_text(dir / "times.txt", times);
  write_text(dir / "calib.txt", kKittiCalib);
}

TEST(KittiDataset, StereoPairsCalibrationAndPoses) {
  TempDir dir;
  make_kitti(dir.path(), 3, true);
  write_text(dir / "poses.txt",
             "1 0 0 0 0 1 0 0 0 0 1 0\n"
             "1 0 0 0 0 1 0 0 0 0 1 0.5\n"
             "0 -1 0 2 1 0 0 0 0 0 1 1.0\n");
  const auto dataset = open_dataset(dir.path().string());
  EXPECT_EQ(dataset->layout(), "kitti");
  EXPECT_EQ(dataset->sensor(), SensorKind::kStereo);
  ASSERT_EQ(dataset->size(), 3u);
  EXPECT_DOUBLE_EQ(dataset->frame_info(2).timestamp_s, 0.2);
  const auto images = dataset->load(1);
  EXPECT_EQ(images.colour.at<uchar>(0, 0), 1);
  EXPECT_EQ(images.right.at<uchar>(0, 0), 101);
  const auto& gt = dataset->ground_truth();
  ASSERT_EQ(gt.size(), 3u);
  EXPECT_DOUBLE_EQ(gt[1].timestamp_s, 0.1);
  EXPECT_DOUBLE_EQ(gt[1].world_from_cam.translation().z(), 0.5);
  // Third pose: camera x axis maps to world +y.
  const geometry::Vec3 x_axis = gt[2].world_from_cam.rotation() * geometry::Vec3(1, 0, 0);
  EXPECT_NEAR(x_axis.y(), 1.0, 1e-12);
  const auto* kitti = dynamic_cast<const KittiDataset*>(dataset.get());
  ASSERT_NE(kitti, nullptr);
  EXPECT_DOUBLE_EQ(kitti->calibration().fx, 700.0);
  EXPECT_DOUBLE_EQ(kitti->calibration().fy, 710.0);
  EXPECT_DOUBLE_EQ(kitti->calibration().cy, 180.0);
  EXPECT_DOUBLE_EQ(kitti->calibration().bf, 378.0);  // -P1[3]
}

TEST(KittiDataset, OfficialLayoutPosesBesideSequences) {
  TempDir root;
  const auto dir = root / "dataset/sequences/05";
  make_kitti(dir, 2, false);
  write_text(root / "dataset/poses/05.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 3 0 1 0 0 0 0 1 0\n");
  const auto dataset = open_dataset(dir.string() + "/");
  EXPECT_EQ(dataset->sensor(), SensorKind::kMonocular);
  ASSERT_EQ(dataset->ground_truth().size(), 2u);
  EXPECT_DOUBLE_EQ(dataset->ground_truth()[1].world_from_cam.translation().x(), 3.0);
}

TEST(KittiDatasetErrors, MissingImageNamesTimesLineAndFile) {
  TempDir dir;
  make_kitti(dir.path(), 3, true);
  std::filesystem::remove(dir / "image_1/000002.png");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("times.txt:3:"), std::string::npos) << message;
  EXPECT_NE(message.find("image_1/000002.png"), std::string::npos) << message;
}

TEST(KittiDatasetErrors, CalibrationWithoutP0NamesFile) {
  TempDir dir;
  make_kitti(dir.path(), 1, false);
  write_text(dir / "calib.txt", "P1: 700 0 600 -378 0 710 180 0 0 0 1 0\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("calib.txt"), std::string::npos) << message;
  EXPECT_NE(message.find("P0"), std::string::npos) << message;
}

TEST(KittiDatasetErrors, PosesWithTooFewFieldsNamesLine) {
  TempDir dir;
  make_kitti(dir.path(), 2, false);
  write_text(dir / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("poses.txt:2:"), std::string::npos) << message;
}

void make_euroc(const std::filesystem::path& dir, const std::vector<long long>& left_ns,
                const std::vector<long long>& right_ns) {
  const std::string yaml =
      "%YAML:1.0\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, "
      "1.0, 0.0, "
      "0.0, 0.0, 0.0, 1.0]\nrate_hz: 20\nresolution: [8, 6]\ncamera_model: pinhole\n"
      "intrinsics: [400.0, 401.0, 4.0, 3.0] #fu, fv, cu, cv\ndistortion_model: radial-tangential\n"
      "distortion_coefficients: [-0.1, 0.01, 0.0, 0.0]\n";
  for (const auto& [cam, stamps] : {std::pair{"cam0", left_ns}, {"cam1", right_ns}}) {
    std::string csv = "#timestamp [ns],filename\n";
    for (const long long ns : stamps) {
      test::write_grey(dir / "mav0" / cam / "data" / (std::to_string(ns) + ".png"),
                       static_cast<int>(ns % 100));
      csv += std::to_string(ns) + "," + std::to_string(ns) + ".png\n";
    }
    write_text(dir / "mav0" / cam / "data.csv", csv);
    write_text(dir / "mav0" / cam / "sensor.yaml", yaml);
  }
}

TEST(EurocDataset, PairsAreRowsWithEqualStamps) {
  TempDir dir;
  make_euroc(dir.path(), {1000000000, 1050000000, 1100000000}, {1000000000, 1100000000, 1150000000});
  write_text(
      dir / "mav0/state_groundtruth_estimate0/data.csv",
      "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n"
      "1000000000,1.0,2.0,3.0,1.0,0.0,0.0,0.0\n");
  const auto dataset = open_euroc_dataset(dir.path().string());
  ASSERT_EQ(dataset->size(), 2u);
  EXPECT_DOUBLE_EQ(dataset->frame_info(1).timestamp_s, 1.1);
  EXPECT_EQ(dataset->load(1).right.at<uchar>(0, 0), 0);  // 1100000000 % 100
  const auto s = dataset->summary();
  EXPECT_EQ(s.colour_entries, 3u);
  EXPECT_EQ(s.right_entries, 3u);
  ASSERT_EQ(dataset->ground_truth().size(), 1u);
  EXPECT_DOUBLE_EQ(dataset->ground_truth()[0].timestamp_s, 1.0);
  EXPECT_DOUBLE_EQ(dataset->ground_truth()[0].world_from_cam.translation().z(), 3.0);
  EXPECT_DOUBLE_EQ(dataset->left_calibration().intrinsics[1], 401.0);
  // Also found when given the mav0 folder itself.
  EXPECT_EQ(open_dataset((dir / "mav0").string())->size(), 2u);
}

TEST(EurocDatasetErrors, BadSensorYamlNamesFileAndKey) {
  TempDir dir;
  make_euroc(dir.path(), {1000000000}, {1000000000});
  write_text(dir / "mav0/cam1/sensor.yaml", "%YAML:1.0\nintrinsics: [400.0, 401.0, 4.0]\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("cam1/sensor.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("intrinsics"), std::string::npos) << message;
}

TEST(EurocDatasetErrors, NonNumericStampNamesCsvLine) {
  TempDir dir;
  make_euroc(dir.path(), {1000000000}, {1000000000});
  write_text(dir / "mav0/cam0/data.csv", "#timestamp [ns],filename\n12x,1000000000.png\n");
  const auto message = error_of([&] { (void)open_dataset(dir.path().string()); });
  EXPECT_NE(message.find("cam0/data.csv:2:"), std::string::npos) << message;
}

TEST(ImageFolder, SortedImagesWithStampsFromFps) {
  TempDir dir;
  test::write_colour(dir / "b.png", 2);
  test::write_colour(dir / "a.jpg", 1);
  test::write_colour(dir / "c.PNG", 3);
  write_text(dir / "readme.md", "not an image\n");
  DatasetOptions options;
  options.fps = 10.0;
  const auto dataset = open_dataset(dir.path().string(), options);
  EXPECT_EQ(dataset->layout(), "images");
  ASSERT_EQ(dataset->size(), 3u);
  EXPECT_EQ(std::filesystem::path(dataset->frame_info(0).colour_path).filename(), "a.jpg");
  EXPECT_DOUBLE_EQ(dataset->frame_info(2).timestamp_s, 0.2);
  EXPECT_DOUBLE_EQ(open_dataset(dir.path().string())->frame_info(1).timestamp_s,
                   1.0 / 30.0);  // default 30 fps
}

TEST(VideoSource, ReadsEveryFrameSequentiallyWithStampsFromFps) {
  TempDir dir;
  const std::string path = (dir / "clip.avi").string();
  {
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(64, 48));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 5; ++i) writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(40 * i, 40 * i, 40 * i)));
  }
  const auto source = open_source(path);
  EXPECT_EQ(source->layout(), "video");
  EXPECT_EQ(source->sensor(), SensorKind::kMonocular);
  std::vector<double> stamps;
  std::vector<double> brightness;
  while (auto frame = source->next()) {
    stamps.push_back(frame->info.timestamp_s);
    brightness.push_back(cv::mean(frame->images.colour)[0]);
    EXPECT_EQ(frame->images.colour.size(), cv::Size(64, 48));
  }
  ASSERT_EQ(stamps.size(), 5u);
  EXPECT_DOUBLE_EQ(stamps[4], 0.4);
  EXPECT_NEAR(brightness[3], 120.0, 3.0);  // MJPEG is lossy
}

TEST(VideoSourceErrors, FileThatIsNotAVideoNamesIt) {
  TempDir dir;
  write_text(dir / "clip.avi", "definitely not a video");
  const std::string path = (dir / "clip.avi").string();
  const auto message = error_of([&] { (void)open_source(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
}

TEST(OpenSource, MissingPathNamesIt) {
  const auto message = error_of([] { (void)open_source("/nonexistent/clip.mp4"); });
  EXPECT_NE(message.find("/nonexistent/clip.mp4"), std::string::npos) << message;
}

}  // namespace
}  // namespace crowdslam::io
