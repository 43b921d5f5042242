// Settings files on bad input (issue 10): unknown and duplicated keys, integer overflow, values the
// components would reject, image size against Camera.width/height, which camera the file describes.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "crowdslam/io/settings.h"
#include "log_capture.h"
#include "test_support.h"

namespace crowdslam::io {
namespace {

namespace fs = std::filesystem;
using test::error_of;
using test::TempDir;
using test::write_text;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::string config(const std::string& name) { return (test::source_dir() / "config" / name).string(); }

// config/TUM1.yaml with `extra` appended; returns the path and, in `first_extra_line`, the line number of
// the first appended line.
std::string tum1_plus(const TempDir& dir, const std::string& extra, int* first_extra_line = nullptr) {
  std::string text = test::read_text(config("TUM1.yaml"));
  if (!text.empty() && text.back() != '\n') text += '\n';
  if (first_extra_line) *first_extra_line = static_cast<int>(std::count(text.begin(), text.end(), '\n')) + 1;
  const std::string path = (dir / "settings.yaml").string();
  write_text(path, text + extra);
  return path;
}

// config/TUM1.yaml with `key`'s line replaced.
std::string tum1_with(const TempDir& dir, const std::string& key, const std::string& replacement) {
  std::string text = test::read_text(config("TUM1.yaml"));
  const std::regex line("(^|\n)" + std::regex_replace(key, std::regex("\\."), "\\.") + ":[^\n]*");
  EXPECT_TRUE(std::regex_search(text, line)) << key;
  const std::string path = (dir / "settings.yaml").string();
  write_text(path, std::regex_replace(text, line, "$1" + replacement));
  return path;
}

TEST(SettingsKeys, UnknownKeyIsWarnedWithFileLineAndTheClosestKnownKey) {
  TempDir dir;
  int line = 0;
  const std::string path =
      tum1_plus(dir, "Camera.fxx: 517.3\nRGBD.DepthMapFactor: 5000.0\nFoo.bar: 1\n", &line);
  test::LogCapture log;
  const Settings s = load_settings(path, SensorKind::kRgbd);
  EXPECT_DOUBLE_EQ(s.camera.fx, 517.306408);  // the known key is read, the unknown one ignored
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 3u);
  EXPECT_EQ(warnings[0], path + ":" + std::to_string(line) +
                             ": Camera.fxx: unknown key, ignored (did you mean Camera.fx?)");
  EXPECT_TRUE(contains(warnings[1], ":" + std::to_string(line + 1) +
                                        ": RGBD.DepthMapFactor: unknown key, ignored "
                                        "(did you mean DepthMapFactor?)"))
      << warnings[1];
  EXPECT_EQ(warnings[2], path + ":" + std::to_string(line + 2) + ": Foo.bar: unknown key, ignored");
}

TEST(SettingsKeys, ManyUnknownKeysAreWarnedTenTimesThenCounted) {
  TempDir dir;
  std::string extra;
  for (int i = 0; i < 13; ++i) extra += "Unknown.key" + std::to_string(i) + ": 1\n";
  const std::string path = tum1_plus(dir, extra);
  test::LogCapture log;
  (void)load_settings(path, SensorKind::kRgbd);
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 11u);
  EXPECT_EQ(warnings.back(), path + ": 3 more unknown keys ignored");
}

TEST(SettingsKeys, OrbSlamKeysWeDoNotUseAreAcceptedSilently) {
  TempDir dir;
  // The keys ORB-SLAM2's published TUM/EuRoC/KITTI files carry beside the ones we read.
  const std::string path =
      tum1_plus(dir,
                "Camera.type: \"PinHole\"\nCamera.bFishEye: 0\nFile.version: \"1.0\"\n"
                "Viewer.KeyFrameSize: 0.05\nViewer.KeyFrameLineWidth: 1\nViewer.GraphLineWidth: 0.9\n"
                "Viewer.PointSize:2\nViewer.CameraSize: 0.08\nViewer.CameraLineWidth: 3\n"
                "Viewer.ViewpointX: 0\nViewer.ViewpointY: -0.7\nViewer.ViewpointZ: -1.8\n"
                "Viewer.ViewpointF: 500\nIMU.Frequency: 200\n");
  test::LogCapture log;
  EXPECT_NO_THROW((void)load_settings(path, SensorKind::kRgbd));
  EXPECT_TRUE(log.warnings().empty()) << log.warnings().front();
}

TEST(SettingsKeys, ShippedConfigFilesHaveNoUnknownKeys) {
  for (const auto& entry : fs::directory_iterator(test::source_dir() / "config")) {
    const std::string name = entry.path().filename().string();
    SCOPED_TRACE(name);
    const SensorKind sensor =
        name.rfind("TUM", 0) == 0 || name.rfind("Bonn", 0) == 0 ? SensorKind::kRgbd : SensorKind::kStereo;
    test::LogCapture log;
    EXPECT_NO_THROW((void)load_settings(entry.path().string(), sensor));
    EXPECT_TRUE(log.warnings().empty()) << log.warnings().front();
  }
}

TEST(SettingsKeys, KeySetTwiceIsAnErrorNamingBothLines) {
  TempDir dir;
  int line = 0;
  const std::string path = tum1_plus(dir, "Camera.fx: 500.0\n", &line);
  const std::string text = test::read_text(path);
  const int first =
      static_cast<int>(std::count(text.begin(), text.begin() + text.find("Camera.fx:"), '\n')) + 1;
  const std::string message = error_of([&] { (void)load_settings(path, SensorKind::kRgbd); });
  EXPECT_EQ(message, path + ":" + std::to_string(line) + ": Camera.fx: set twice (first on line " +
                         std::to_string(first) + ")");
}

TEST(SettingsValues, IntegerTooLargeIsOutOfRangeNotAWrongNumber) {
  TempDir dir;
  for (const std::string value : {"100000000000000000000", "1e20", "-3000000000"}) {
    SCOPED_TRACE(value);
    const std::string path = tum1_with(dir, "ORBextractor.nFeatures", "ORBextractor.nFeatures: " + value);
    const std::string message = error_of([&] { (void)load_settings(path, SensorKind::kRgbd); });
    EXPECT_TRUE(contains(message, path + ": ORBextractor.nFeatures: ")) << message;
    EXPECT_TRUE(contains(message, "out of range for an integer")) << message;  // used to be "got -1"
    EXPECT_FALSE(contains(message, "-1,")) << message;
  }
  const std::string path = tum1_with(dir, "Camera.width", "Camera.width: 99999999999");
  EXPECT_TRUE(contains(error_of([&] { (void)load_settings(path, SensorKind::kRgbd); }),
                       "Camera.width: 99999999999 is out of range for an integer"));
}

struct Bound {
  const char* key;
  const char* line;
  const char* expected;  // after "FILE: "
};

class SettingsComponentBounds : public ::testing::TestWithParam<Bound> {};

// Values the components (ORB extractor, feature budget, detector, tracker) reject must be reported by
// the settings, naming file and key: the ORB extractor's own message named neither.
TEST_P(SettingsComponentBounds, AreReportedWithFileAndKey) {
  TempDir dir;
  const Bound& b = GetParam();
  const std::string path = tum1_with(dir, b.key, b.line);
  const std::string message = error_of([&] { (void)load_settings(path, SensorKind::kRgbd); });
  EXPECT_TRUE(contains(message, path + ": " + b.expected)) << message;
}

INSTANTIATE_TEST_SUITE_P(
    Components, SettingsComponentBounds,
    ::testing::Values(
        Bound{"ORBextractor.iniThFAST", "ORBextractor.iniThFAST: 300",
              "ORBextractor.iniThFAST: must be <= 254"},
        Bound{"ORBextractor.nFeatures", "ORBextractor.nFeatures: 2000000000",
              "ORBextractor.nFeatures: must be <= 100000"},
        Bound{"ORBextractor.scaleFactor", "ORBextractor.scaleFactor: 1.00000001",
              "ORBextractor.scaleFactor: must be > 1"},
        Bound{"ORBextractor.scaleFactor", "ORBextractor.scaleFactor: 100.0",
              "ORBextractor.scaleFactor: must be <= 4"},
        Bound{"Camera.fps", "Camera.fps: 1e300", "Camera.fps: must be <= 10000"},
        Bound{"Camera.width", "Camera.width: 70000", "Camera.width: must be <= 65535"},
        Bound{"Detector.input_size", "Detector.input_size: 320000", "Detector.input_size: must be <= 2048"},
        Bound{"FeatureBudget.factors", "FeatureBudget.factors: [ 1.0, 1.3, 1.5, 1.7, 1.9, 1e300 ]",
              "FeatureBudget.factors: must be <= 10"}));

TEST(SettingsCamera, DepthMapFactorAndBaselineSayWhichCameraTheFileDescribes) {
  const Settings rgbd = load_settings(config("TUM1.yaml"), SensorKind::kMonocular);
  EXPECT_TRUE(rgbd.has_depth_map_factor);
  EXPECT_TRUE(rgbd.has_baseline);
  const Settings stereo = load_settings(config("KITTI04-12.yaml"), SensorKind::kMonocular);
  EXPECT_FALSE(stereo.has_depth_map_factor);
  EXPECT_TRUE(stereo.has_baseline);
  TempDir dir;
  std::string text = test::read_text(config("TUM1.yaml"));
  text = std::regex_replace(text, std::regex("\n(DepthMapFactor|Camera\\.bf):[^\n]*"), "\n");
  write_text(dir / "mono.yaml", text);
  const Settings mono = load_settings((dir / "mono.yaml").string(), SensorKind::kMonocular);
  EXPECT_FALSE(mono.has_depth_map_factor);
  EXPECT_FALSE(mono.has_baseline);
  // write_settings keeps the distinction.
  write_settings((dir / "back.yaml").string(), mono);
  const Settings back = load_settings((dir / "back.yaml").string(), SensorKind::kMonocular);
  EXPECT_FALSE(back.has_depth_map_factor);
  EXPECT_FALSE(back.has_baseline);
  EXPECT_TRUE(back == mono);
}

TEST(SettingsCamera, ImageSizeIsCheckedAgainstCameraWidthAndHeight) {
  const Settings s = load_settings(config("Bonn.yaml"), SensorKind::kRgbd);
  EXPECT_NO_THROW(check_image_size(s, {640, 480}, "rgb/1.jpg"));
  const std::string message = error_of([&] { check_image_size(s, {320, 240}, "rgb/1.jpg"); });
  EXPECT_EQ(message, "rgb/1.jpg: image is 320x240, but the settings " + config("Bonn.yaml") +
                         " give Camera.width/height 640x480 (settings for another camera?)");
  Settings unknown_size = s;
  unknown_size.camera.width = 0;
  unknown_size.camera.height = 0;
  EXPECT_NO_THROW(check_image_size(unknown_size, {320, 240}, "rgb/1.jpg"));  // nothing to compare with
}

}  // namespace
}  // namespace crowdslam::io
