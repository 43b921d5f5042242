// write_sequence: files and formats, round trip through the PNGs, determinism, bad options, atomicity.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"
#include "synth_test_util.h"
#include "test_support.h"

namespace crowdslam::synth {
namespace {
namespace fs = std::filesystem;
using crowdslam::test::read_text;
using crowdslam::test::TempDir;

SynthOptions small_options() {
  SynthOptions o;
  o.width = 160;
  o.height = 120;
  o.frames = 10;
  o.trajectory = TrajectoryKind::kSweep;
  return o;
}

// Data lines (not '#') of a text file, split into fields.
std::vector<std::vector<std::string>> data_lines(const fs::path& path) {
  std::vector<std::vector<std::string>> out;
  for (const std::string& line : read_lines(path.string())) {
    if (!line.empty() && line[0] != '#') out.push_back(split_fields(line));
  }
  return out;
}

double yaml_value(const fs::path& path, const std::string& key) {
  for (const std::string& line : read_lines(path.string())) {
    if (line.rfind(key + ":", 0) == 0) return *parse_double(trim(line.substr(key.size() + 1)));
  }
  ADD_FAILURE() << key << " missing in " << path;
  return 0.0;
}

TEST(SynthWriter, RgbdFilesRoundTripConsistently) {
  TempDir tmp;
  const fs::path dir = tmp / "seq";
  const SequenceSummary summary = write_sequence(small_options(), dir);
  EXPECT_EQ(summary.frames, 10);
  const auto rgb = data_lines(dir / "rgb.txt");
  const auto depth = data_lines(dir / "depth.txt");
  ASSERT_EQ(rgb.size(), 10u);
  ASSERT_EQ(depth.size(), 10u);
  for (int i = 0; i < 10; ++i) {
    EXPECT_NEAR(*parse_double(rgb[i][0]), 1.0 + i / 30.0, 1e-6);
    EXPECT_EQ(rgb[i][0], depth[i][0]);
    EXPECT_TRUE(fs::is_regular_file(dir / rgb[i][1]));
  }
  const io::Trajectory gt = io::read_tum_trajectory((dir / "groundtruth.txt").string());
  ASSERT_EQ(gt.size(), 10u);
  Intrinsics k;
  k.width = static_cast<int>(yaml_value(dir / "settings.yaml", "Camera.width"));
  k.height = static_cast<int>(yaml_value(dir / "settings.yaml", "Camera.height"));
  k.fx = yaml_value(dir / "settings.yaml", "Camera.fx");
  k.fy = yaml_value(dir / "settings.yaml", "Camera.fy");
  k.cx = yaml_value(dir / "settings.yaml", "Camera.cx");
  k.cy = yaml_value(dir / "settings.yaml", "Camera.cy");
  const double factor = yaml_value(dir / "settings.yaml", "DepthMapFactor");
  EXPECT_EQ(k.width, 160);
  EXPECT_NEAR(k.fx, 525.0 / 4.0, 1e-6);
  EXPECT_NEAR(k.cx, 79.5, 1e-6);
  const auto load = [&](int i, cv::Mat& colour, cv::Mat& depth_m) {
    colour = cv::imread((dir / rgb[i][1]).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat raw = cv::imread((dir / depth[i][1]).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(colour.type(), CV_8UC3);
    ASSERT_EQ(raw.type(), CV_16U);
    raw.convertTo(depth_m, CV_32F, 1.0 / factor);
  };
  for (const auto& [i, j] : {std::pair{0, 5}, std::pair{4, 9}}) {
    cv::Mat ci, di, cj, dj;
    load(i, ci, di);
    load(j, cj, dj);
    const auto c = test::check_consistency(ci, di, {}, gt[i].world_from_cam, cj, dj, {}, gt[j].world_from_cam, k, 1);
    EXPECT_GT(c.inside, c.sampled / 3);
    EXPECT_GT(c.depth_agrees, 0.85 * c.inside);
    EXPECT_LT(c.median_grey_diff, 4.0);
  }
  const std::string json = read_text(dir / "synth.json");
  EXPECT_NE(json.find("\"seed\": 1"), std::string::npos);
  EXPECT_NE(json.find("\"trajectory\": \"sweep\""), std::string::npos);
}

TEST(SynthWriter, PeopleFileListsTheVisiblePeopleWithTheirBoxes) {
  TempDir tmp;
  SynthOptions o = small_options();
  o.frames = 60;
  o.people = 3;
  o.trajectory = TrajectoryKind::kLoop;
  write_sequence(o, tmp / "seq");
  const Scene scene = Scene::build(o);
  std::vector<std::vector<std::string>> expected;
  for (int f = 0; f < o.frames; ++f) {
    const RenderedFrame r = render_frame(scene, f);
    for (const PersonBox& b : visible_person_boxes(scene, r, scene.trajectory()[f].world_from_cam, f)) {
      expected.push_back({std::to_string(f + 1), std::to_string(b.id)});
      EXPECT_GE(b.box.x, 0.0);
      EXPECT_LE(b.box.x + b.box.width, o.width - 1.0 + 1e-9);
    }
  }
  const auto lines = data_lines(tmp / "seq" / "people_gt.txt");
  ASSERT_EQ(lines.size(), expected.size());
  ASSERT_FALSE(lines.empty()) << "with 3 people someone should be seen in 60 frames";
  for (size_t i = 0; i < lines.size(); ++i) {
    ASSERT_EQ(lines[i].size(), 10u);
    EXPECT_EQ(lines[i][0], expected[i][0]);
    EXPECT_EQ(lines[i][1], expected[i][1]);
    EXPECT_EQ(lines[i][6], "1");
    EXPECT_EQ(lines[i][9], "-1");
  }
}

TEST(SynthWriter, SameSeedSameBytesOtherSeedDiffers) {
  TempDir tmp;
  SynthOptions o = small_options();
  o.frames = 4;
  o.people = 2;
  o.noise_depth_m = 0.01;
  write_sequence(o, tmp / "a");
  write_sequence(o, tmp / "b");
  o.seed = 2;
  write_sequence(o, tmp / "c");
  int compared = 0;
  for (const auto& entry : fs::recursive_directory_iterator(tmp / "a")) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), tmp / "a");
    EXPECT_EQ(read_text(tmp / "a" / rel), read_text(tmp / "b" / rel)) << rel;
    ++compared;
  }
  EXPECT_EQ(compared, 4 * 2 + 6);  // PNGs, rgb/depth/groundtruth/people_gt .txt, settings, synth.json
  EXPECT_NE(read_text(tmp / "a" / "rgb" / "000000.png"), read_text(tmp / "c" / "rgb" / "000000.png"));
  EXPECT_NE(read_text(tmp / "a" / "depth" / "000001.png"), read_text(tmp / "c" / "depth" / "000001.png"));
}

TEST(SynthWriter, StereoWritesKittiLayout) {
  TempDir tmp;
  SynthOptions o = small_options();
  o.frames = 3;
  o.stereo = true;
  write_sequence(o, tmp / "seq");
  const fs::path dir = tmp / "seq";
  for (const char* name : {"image_0/000002.png", "image_1/000002.png", "groundtruth.txt", "people_gt.txt",
                           "synth.json", "settings.yaml"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / name)) << name;
  }
  EXPECT_FALSE(fs::exists(dir / "depth"));
  const auto times = data_lines(dir / "times.txt");
  ASSERT_EQ(times.size(), 3u);
  EXPECT_NEAR(*parse_double(times[2][0]), 1.0 + 2.0 / 30.0, 1e-6);
  const auto calib = data_lines(dir / "calib.txt");
  ASSERT_EQ(calib.size(), 4u);
  const double fx = 525.0 / 4.0;
  EXPECT_EQ(calib[1][0], "P1:");
  ASSERT_EQ(calib[1].size(), 13u);
  EXPECT_NEAR(*parse_double(calib[1][1]), fx, 1e-9);
  EXPECT_NEAR(*parse_double(calib[1][4]), -fx * 0.12, 1e-9);
  EXPECT_NEAR(*parse_double(calib[0][4]), 0.0, 1e-12);
  EXPECT_NEAR(yaml_value(dir / "settings.yaml", "Camera.bf"), fx * 0.12, 1e-6);
  const io::Trajectory kitti = io::read_kitti_trajectory((dir / "poses.txt").string());
  const io::Trajectory tum = io::read_tum_trajectory((dir / "groundtruth.txt").string());
  ASSERT_EQ(kitti.size(), 3u);
  ASSERT_EQ(tum.size(), 3u);
  EXPECT_LT((kitti[2].world_from_cam.translation() - tum[2].world_from_cam.translation()).norm(), 1e-6);
  const cv::Mat right = cv::imread((dir / "image_1/000000.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(right.type(), CV_8UC3);
  EXPECT_EQ(right.cols, 160);
}

TEST(SynthWriter, DepthNoiseHasTheRequestedSigma) {
  TempDir tmp;
  SynthOptions o = small_options();
  o.frames = 1;
  o.noise_depth_m = 0.02;
  write_sequence(o, tmp / "seq");
  const cv::Mat raw = cv::imread((tmp / "seq" / "depth" / "000000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16U);
  const RenderedFrame exact = render_frame(Scene::build(o), 0);
  double sum = 0.0;
  double sum_sq = 0.0;
  int n = 0;
  for (int y = 0; y < raw.rows; ++y) {
    for (int x = 0; x < raw.cols; ++x) {
      const double d = raw.at<std::uint16_t>(y, x) / 5000.0 - exact.depth_m.at<float>(y, x);
      sum += d;
      sum_sq += d * d;
      ++n;
    }
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.0, 0.002);
  EXPECT_NEAR(std::sqrt(sum_sq / n - mean * mean), 0.02, 0.002);
}

TEST(SynthWriter, BadOptionsNameTheOption) {
  const auto message_of = [](SynthOptions o) {
    try {
      o.check();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  SynthOptions o;
  o.frames = 0;
  EXPECT_NE(message_of(o).find("--frames"), std::string::npos);
  o = SynthOptions();
  o.people = -1;
  EXPECT_NE(message_of(o).find("--people"), std::string::npos);
  o = SynthOptions();
  o.width = 0;
  EXPECT_NE(message_of(o).find("--width"), std::string::npos);
  o = SynthOptions();
  o.noise_depth_m = -0.1;
  EXPECT_NE(message_of(o).find("--noise-depth"), std::string::npos);
  EXPECT_EQ(message_of(SynthOptions()), "");
  try {
    parse_trajectory_kind("zigzag");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("zigzag"), std::string::npos);
  }
  EXPECT_EQ(parse_trajectory_kind("handheld"), TrajectoryKind::kHandheld);
}

TEST(SynthWriter, RefusesToOverwriteUnlessForcedAndLeavesNoTemporaries) {
  TempDir tmp;
  const fs::path dir = tmp / "seq";
  fs::create_directories(dir);
  crowdslam::test::write_text(dir / "keep.txt", "mine");
  SynthOptions o = small_options();
  o.frames = 2;
  try {
    write_sequence(o, dir);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos);
  }
  EXPECT_EQ(read_text(dir / "keep.txt"), "mine");
  o.force = true;
  write_sequence(o, dir);
  EXPECT_FALSE(fs::exists(dir / "keep.txt"));
  EXPECT_TRUE(fs::exists(dir / "rgb" / "000001.png"));
  // A failing run (parent is a file) leaves nothing behind.
  crowdslam::test::write_text(tmp / "file", "x");
  EXPECT_THROW(write_sequence(o, tmp / "file" / "seq"), std::exception);
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(tmp.path())) ++entries;
  EXPECT_EQ(entries, 2);  // seq and file only: no *.tmp-* directory
}

}  // namespace
}  // namespace crowdslam::synth
