#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "crowdslam/io/settings.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::io {
namespace {

using test::TempDir;
using test::write_text;

using test::error_of;

std::string config(const std::string& name) { return (test::source_dir() / "config" / name).string(); }

// A copy of config/TUM1.yaml with `key`'s line replaced by `replacement` (removed when empty).
std::string tum1_with(const TempDir& dir, const std::string& key, const std::string& replacement) {
  std::string text = test::read_text(config("TUM1.yaml"));
  const std::regex line("(^|\n)" + std::regex_replace(key, std::regex("\\."), "\\.") + ":[^\n]*");
  EXPECT_TRUE(std::regex_search(text, line)) << key;
  text = std::regex_replace(text, line, "$1" + replacement);
  const std::string path = (dir / "settings.yaml").string();
  write_text(path, text);
  return path;
}

TEST(ShippedSettings, TumFilesHaveThePublishedCalibration) {
  struct Expected {
    const char* file;
    double fx, fy, cx, cy, k1, k3;
  };
  for (const auto& e :
       {Expected{"TUM1.yaml", 517.306408, 516.469215, 318.643040, 255.313989, 0.262383, 1.163314},
        Expected{"TUM2.yaml", 520.908620, 521.007327, 325.141442, 249.701764, 0.231222, 0.917205},
        Expected{"TUM3.yaml", 535.4, 539.2, 320.1, 247.6, 0.0, 0.0},
        Expected{"Bonn.yaml", 542.822841, 542.576870, 315.593520, 237.756098, 0.0, 0.0}}) {
    SCOPED_TRACE(e.file);
    const Settings s = load_settings(config(e.file), SensorKind::kRgbd);
    EXPECT_DOUBLE_EQ(s.camera.fx, e.fx);
    EXPECT_DOUBLE_EQ(s.camera.fy, e.fy);
    EXPECT_DOUBLE_EQ(s.camera.cx, e.cx);
    EXPECT_DOUBLE_EQ(s.camera.cy, e.cy);
    EXPECT_DOUBLE_EQ(s.camera.k1, e.k1);
    EXPECT_DOUBLE_EQ(s.camera.k3, e.k3);
    EXPECT_EQ(s.camera.width, 640);
    EXPECT_EQ(s.camera.height, 480);
    EXPECT_DOUBLE_EQ(s.camera.bf, 40.0);
    EXPECT_DOUBLE_EQ(s.depth_map_factor, 5000.0);
    EXPECT_DOUBLE_EQ(s.th_depth, 40.0);
    EXPECT_EQ(s.orb.n_features, 1000);
    EXPECT_DOUBLE_EQ(s.orb.scale_factor, 1.2);
    EXPECT_EQ(s.orb.n_levels, 8);
    EXPECT_EQ(s.orb.ini_th_fast, 20);
    EXPECT_EQ(s.orb.min_th_fast, 7);
    EXPECT_FALSE(s.rectification.has_value());
    EXPECT_EQ(s.people_filter.mode, "depth");
  }
}

TEST(ShippedSettings, KittiFilesHaveThePublishedCalibration) {
  struct Expected {
    const char* file;
    double f, cx, cy, bf;
    int width, height;
  };
  for (const auto& e : {Expected{"KITTI00-02.yaml", 718.856, 607.1928, 185.2157, 386.1448, 1241, 376},
                        Expected{"KITTI03.yaml", 721.5377, 609.5593, 172.854, 387.5744, 1242, 375},
                        Expected{"KITTI04-12.yaml", 707.0912, 601.8873, 183.1104, 379.8145, 1226, 370}}) {
    SCOPED_TRACE(e.file);
    const Settings s = load_settings(config(e.file), SensorKind::kStereo);
    EXPECT_DOUBLE_EQ(s.camera.fx, e.f);
    EXPECT_DOUBLE_EQ(s.camera.fy, e.f);
    EXPECT_DOUBLE_EQ(s.camera.cx, e.cx);
    EXPECT_DOUBLE_EQ(s.camera.cy, e.cy);
    EXPECT_DOUBLE_EQ(s.camera.bf, e.bf);
    EXPECT_EQ(s.camera.width, e.width);
    EXPECT_EQ(s.camera.height, e.height);
    EXPECT_DOUBLE_EQ(s.camera.fps, 10.0);
    EXPECT_DOUBLE_EQ(s.th_depth, 35.0);
    EXPECT_EQ(s.orb.n_features, 2000);
    EXPECT_TRUE(s.ground.enabled);  // a car's camera: monocular runs hold the ground
    EXPECT_DOUBLE_EQ(s.ground.keyframe_sigma, 0.01);
  }
}

TEST(ShippedSettings, EurocRectificationMakesTheCamerasParallel) {
  const Settings s = load_settings(config("EuRoC.yaml"), SensorKind::kStereo);
  ASSERT_TRUE(s.rectification.has_value());
  const auto& left = s.rectification->left;
  const auto& right = s.rectification->right;
  // Raw calibration of V1_01_easy's cam0 / cam1 (sensor.yaml).
  EXPECT_DOUBLE_EQ(left.K.at<double>(0, 0), 458.654);
  EXPECT_DOUBLE_EQ(left.K.at<double>(1, 2), 248.375);
  EXPECT_DOUBLE_EQ(left.D.at<double>(0, 0), -0.28340811);
  EXPECT_DOUBLE_EQ(right.K.at<double>(0, 0), 457.587);
  EXPECT_EQ(left.width, 752);
  EXPECT_EQ(s.camera.width, 752);
  EXPECT_EQ(s.orb.n_features, 1200);
  EXPECT_DOUBLE_EQ(s.camera.fps, 20.0);
  // right_from_left from the two T_BS of sensor.yaml: inverse(T_BS1) * T_BS0.
  cv::Mat body_from_cam0 =
      (cv::Mat_<double>(4, 4) << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
       0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768, -0.0257744366974, 0.00375618835797,
       0.999660727178, 0.00981073058949, 0, 0, 0, 1);
  cv::Mat body_from_cam1 =
      (cv::Mat_<double>(4, 4) << 0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,
       0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024, -0.0253898008918, 0.0179005838253,
       0.999517347078, 0.00786212447038, 0, 0, 0, 1);
  const cv::Mat right_from_left = body_from_cam1.inv() * body_from_cam0;
  const cv::Mat rotation = right_from_left(cv::Rect(0, 0, 3, 3));
  const cv::Mat translation = right_from_left(cv::Rect(3, 0, 1, 3));
  // Rectified frames are parallel: R_right * right_from_left.R * R_left^T = I.
  const cv::Mat relative = right.R * rotation * left.R.t();
  EXPECT_LT(cv::norm(relative - cv::Mat::eye(3, 3, CV_64F), cv::NORM_INF), 1e-9);
  // The baseline lies along the rectified x axis, and bf = |t| * fx.
  const cv::Mat t_rect = right.R * translation;
  EXPECT_NEAR(t_rect.at<double>(1), 0.0, 1e-9);
  EXPECT_NEAR(t_rect.at<double>(2), 0.0, 1e-9);
  EXPECT_NEAR(s.camera.bf, cv::norm(translation) * s.camera.fx, 1e-9);
  EXPECT_DOUBLE_EQ(s.camera.fx, left.P.at<double>(0, 0));
  EXPECT_DOUBLE_EQ(s.camera.bf, -right.P.at<double>(0, 3));
}

TEST(Settings, RoundTripThroughWriteSettings) {
  Settings s = load_settings(config("EuRoC.yaml"), SensorKind::kStereo);
  s.camera.k1 = 0.1 + 0.2;  // not representable in 15 digits
  s.camera.rgb = false;
  s.detector.model_cfg = "models/yolo \"fastest\".cfg";
  s.detector.confidence = 1.0 / 3.0;
  s.detector.filter_before_nms = false;
  s.detector.input_width = 416;
  s.detector.input_height = 256;
  s.detector.backend = "yolox";
  s.detector.preprocess = "bytetrack";
  s.detector.resize = "letterbox";
  s.people_filter.mode = "paper";
  s.people_filter.segment_from_m = 0.25;
  s.feature_budget.thresholds = {0.0, 0.5};
  s.feature_budget.factors = {1.0, 1.25, 3.0};
  s.output.trajectory_format = "kitti";
  s.tracking.odometry_bridge_min_inliers = 0;
  s.tracking.reanchor_max_s = 1.5;
  s.tracking.odometry_sigma_deg = 0.1 + 0.2;
  s.tracking.keyframe_reference_ratio = 0.75;
  s.ground.enabled = true;
  s.ground.keyframe_sigma = 0.1 + 0.2;
  TempDir dir;
  const std::string path = (dir / "out.yaml").string();
  write_settings(path, s);
  const Settings back = load_settings(path, SensorKind::kStereo);
  EXPECT_TRUE(back == s);
  EXPECT_EQ(back.detector.model_cfg, "models/yolo \"fastest\".cfg");
  EXPECT_EQ(back.detector.input_width, 416);
  EXPECT_EQ(back.detector.resize, "letterbox");
  EXPECT_EQ(back.camera.k1, 0.1 + 0.2);
  EXPECT_EQ(back.tracking.odometry_bridge_min_inliers, 0);
  EXPECT_EQ(back.tracking.reanchor_max_s, 1.5);
  EXPECT_EQ(back.tracking.odometry_sigma_deg, 0.1 + 0.2);
  EXPECT_EQ(back.tracking.keyframe_reference_ratio, 0.75);
  EXPECT_EQ(back.people_filter.segment_from_m, 0.25);
  EXPECT_TRUE(back.ground.enabled);
  EXPECT_EQ(back.ground.keyframe_sigma, 0.1 + 0.2);
  // A monocular settings object without rectification also survives.
  Settings mono = load_settings(config("TUM3.yaml"), SensorKind::kMonocular);
  write_settings(path, mono);
  EXPECT_TRUE(load_settings(path, SensorKind::kMonocular) == mono);
}

TEST(Settings, OwnSectionsTakeDefaultsWhenAbsent) {
  TempDir dir;
  std::string text = test::read_text(config("TUM1.yaml"));
  text = text.substr(0, text.find("# Person detector"));
  write_text(dir / "s.yaml", text);
  const Settings s = load_settings((dir / "s.yaml").string(), SensorKind::kRgbd);
  EXPECT_EQ(s.detector.input_size, 160);
  EXPECT_EQ(s.detector.input_width, 0);  // 0 x 0 = the square input_size
  EXPECT_EQ(s.detector.input_height, 0);
  EXPECT_EQ(s.detector.backend, "auto");
  EXPECT_EQ(s.detector.preprocess, "auto");
  EXPECT_EQ(s.detector.resize, "auto");
  EXPECT_DOUBLE_EQ(s.detector.confidence, 0.2);
  EXPECT_DOUBLE_EQ(s.detector.nms, 0.1);
  EXPECT_TRUE(s.people_filter.enabled);
  EXPECT_DOUBLE_EQ(s.people_filter.margin_px, 5.0);
  EXPECT_EQ(s.feature_budget.factors.size(), 6u);
  EXPECT_EQ(s.output.trajectory_format, "tum");
  EXPECT_EQ(s.tracking.odometry_bridge_min_inliers, 50);
  EXPECT_FALSE(s.ground.enabled);
  EXPECT_DOUBLE_EQ(s.ground.keyframe_sigma, 0.01);
}

TEST(Settings, FeatureBudgetFactorTable) {
  const FeatureBudgetSettings b;
  EXPECT_DOUBLE_EQ(b.factor_for(0.0), 1.0);
  EXPECT_DOUBLE_EQ(b.factor_for(0.01), 1.3);
  EXPECT_DOUBLE_EQ(b.factor_for(0.2999), 1.3);
  EXPECT_DOUBLE_EQ(b.factor_for(0.3), 1.5);
  EXPECT_DOUBLE_EQ(b.factor_for(0.6), 1.7);
  EXPECT_DOUBLE_EQ(b.factor_for(0.9), 1.9);
  EXPECT_DOUBLE_EQ(b.factor_for(0.95), 2.2);
  EXPECT_DOUBLE_EQ(b.factor_for(1.0), 2.2);
}

TEST(SettingsErrors, SensorDecidesWhichKeysAreRequired) {
  TempDir dir;
  const std::string path = tum1_with(dir, "Camera.bf", "");
  EXPECT_NO_THROW((void)load_settings(path, SensorKind::kMonocular));
  for (const SensorKind sensor : {SensorKind::kStereo, SensorKind::kRgbd}) {
    const auto message = error_of([&] { (void)load_settings(path, sensor); });
    EXPECT_NE(message.find(path + ": Camera.bf: missing"), std::string::npos) << message;
  }
  const std::string no_factor = tum1_with(dir, "DepthMapFactor", "");
  EXPECT_NO_THROW((void)load_settings(no_factor, SensorKind::kStereo));
  EXPECT_NE(
      error_of([&] { (void)load_settings(no_factor, SensorKind::kRgbd); }).find("DepthMapFactor: missing"),
      std::string::npos);
}

TEST(SettingsErrors, MissingFileAndNonYamlNameTheFile) {
  TempDir dir;
  const std::string missing = (dir / "none.yaml").string();
  EXPECT_NE(error_of([&] { (void)load_settings(missing, SensorKind::kMonocular); }).find(missing),
            std::string::npos);
  const std::string garbage = (dir / "garbage.yaml").string();
  write_text(garbage, "%YAML:1.0\nCamera.fx: [1, 2\n  : : ]]\n");
  const auto message = error_of([&] { (void)load_settings(garbage, SensorKind::kMonocular); });
  EXPECT_NE(message.find(garbage), std::string::npos) << message;
}

struct BadValue {
  const char* key;
  const char* line;      // replacement line ("" = remove the key)
  const char* expected;  // substring of the message after "FILE: "
};

class SettingsBadValue : public ::testing::TestWithParam<BadValue> {};

TEST_P(SettingsBadValue, NamesFileAndKey) {
  const BadValue& bad = GetParam();
  TempDir dir;
  const std::string path = tum1_with(dir, bad.key, bad.line);
  const auto message = error_of([&] { (void)load_settings(path, SensorKind::kRgbd); });
  EXPECT_NE(message.find(path + ": " + bad.expected), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(
    EveryKey, SettingsBadValue,
    ::testing::Values(
        BadValue{"Camera.fx", "", "Camera.fx: missing"},
        BadValue{"Camera.fx", "Camera.fx: -517.3", "Camera.fx: must be > 0"},
        BadValue{"Camera.fy", "Camera.fy: \"big\"", "Camera.fy: expected a number"},
        BadValue{"Camera.cx", "Camera.cx: 700.0", "Camera.cx: must be in (0, Camera.width=640)"},
        BadValue{"Camera.cy", "Camera.cy: -1.0", "Camera.cy"},
        BadValue{"Camera.k1", "", "Camera.k1: missing"},
        BadValue{"Camera.k3", "Camera.k3: .nan", "Camera.k3"},
        BadValue{"Camera.width", "Camera.width: 640.5", "Camera.width: expected an integer"},
        BadValue{"Camera.fps", "Camera.fps: 0", "Camera.fps: must be > 0"},
        BadValue{"Camera.bf", "Camera.bf: -40.0", "Camera.bf: must be > 0"},
        BadValue{"Camera.RGB", "Camera.RGB: 2", "Camera.RGB: expected 0 or 1"},
        BadValue{"ThDepth", "ThDepth: 0.0", "ThDepth: must be > 0"},
        BadValue{"DepthMapFactor", "DepthMapFactor: -5000.0", "DepthMapFactor: must be > 0"},
        BadValue{"ORBextractor.nFeatures", "ORBextractor.nFeatures: 0",
                 "ORBextractor.nFeatures: must be > 0"},
        BadValue{"ORBextractor.scaleFactor", "ORBextractor.scaleFactor: 1.0",
                 "ORBextractor.scaleFactor: must be > 1"},
        BadValue{"ORBextractor.nLevels", "ORBextractor.nLevels: 21",
                 "ORBextractor.nLevels: must be in 1..20"},
        BadValue{"ORBextractor.iniThFAST", "ORBextractor.iniThFAST: 5",
                 "ORBextractor.iniThFAST: must be >= ORBextractor.minThFAST"},
        BadValue{"ORBextractor.minThFAST", "ORBextractor.minThFAST: 0",
                 "ORBextractor.minThFAST: must be > 0"},
        BadValue{"Detector.input_size", "Detector.input_size: 100",
                 "Detector.input_size: must be a positive multiple of 32"},
        BadValue{"Detector.input_size",
                 "Detector.input_size: 160\nDetector.input_width: 100\nDetector.input_height: 256",
                 "Detector.input_width: must be 0 or a positive multiple of 32, got 100"},
        BadValue{"Detector.input_size",
                 "Detector.input_size: 160\nDetector.input_width: 416\nDetector.input_height: 4096",
                 "Detector.input_height: must be <= 2048"},
        BadValue{"Detector.input_size", "Detector.input_size: 160\nDetector.input_width: 416",
                 "Detector.input_height: must be set together with Detector.input_width"},
        BadValue{
            "Detector.input_size", "Detector.input_size: 160\nDetector.backend: \"yolov8\"",
            "Detector.backend: must be \"auto\", \"darknet\", \"yolo-onnx\" or \"yolox\", got \"yolov8\""},
        BadValue{"Detector.input_size", "Detector.input_size: 160\nDetector.preprocess: \"imagenet\"",
                 "Detector.preprocess: must be \"auto\", \"darknet\", \"yolox\" or \"bytetrack\""},
        BadValue{"Detector.input_size", "Detector.input_size: 160\nDetector.resize: \"crop\"",
                 "Detector.resize: must be \"auto\", \"stretch\" or \"letterbox\""},
        BadValue{"Detector.confidence", "Detector.confidence: 1.5", "Detector.confidence: must be in (0, 1]"},
        BadValue{"Detector.nms", "Detector.nms: 0", "Detector.nms: must be in (0, 1]"},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nDetector.raw_box_max_area_ratio: 0.5",
                 "Detector.raw_box_max_area_ratio: must be 0 (off) or >= 1"},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nDetector.latest_interval: 0",
                 "Detector.latest_interval: must be >= 1"},
        BadValue{"Detector.person_class", "Detector.person_class: -1", "Detector.person_class: must be >= 0"},
        BadValue{"Detector.model_cfg", "Detector.model_cfg: 3", "Detector.model_cfg: expected a string"},
        BadValue{"PeopleFilter.mode", "PeopleFilter.mode: \"boxes\"",
                 "PeopleFilter.mode: must be \"paper\" or \"depth\""},
        BadValue{"PeopleFilter.right_image", "PeopleFilter.right_image: \"both\"",
                 "PeopleFilter.right_image: must be \"matched\" or \"boxes\""},
        BadValue{"PeopleFilter.margin_px", "PeopleFilter.margin_px: -2",
                 "PeopleFilter.margin_px: must be >= 0"},
        BadValue{"PeopleFilter.segment_from_m", "PeopleFilter.segment_from_m: -0.1",
                 "PeopleFilter.segment_from_m: must be >= 0"},
        BadValue{"PeopleFilter.static_check_below", "PeopleFilter.static_check_below: -1",
                 "PeopleFilter.static_check_below: must be >= 0"},
        BadValue{"PeopleFilter.static_in_boxes", "PeopleFilter.static_in_boxes: \"sometimes\"",
                 "PeopleFilter.static_in_boxes: must be \"auto\", \"monocular\", \"always\" or \"never\""},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nTracking.odometry_bridge_min_inliers: -1",
                 "Tracking.odometry_bridge_min_inliers: must be >= 0 (0 = off)"},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nTracking.odometry_bridge_min_inliers: 1.5",
                 "Tracking.odometry_bridge_min_inliers: expected an integer"},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nTracking.odometry_sigma_deg: -0.3",
                 "Tracking.odometry_sigma_deg: must be in [0, 90] degrees (0 = off)"},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nTracking.keyframe_reference_ratio: 1.5",
                 "Tracking.keyframe_reference_ratio: must be in (0, 1]"},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nGround.keyframe_sigma: 0",
                 "Ground.keyframe_sigma: must be in (0, 1] (relative to the camera's height)"},
        BadValue{"Detector.nms", "Detector.nms: 0.1\nGround.enabled: 2", "Ground.enabled: expected 0 or 1"},
        BadValue{"FeatureBudget.thresholds", "FeatureBudget.thresholds: [ 0.0, 0.6, 0.3, 0.9, 0.95 ]",
                 "FeatureBudget.thresholds: must be strictly increasing"},
        BadValue{"FeatureBudget.thresholds", "FeatureBudget.thresholds: 0.5",
                 "FeatureBudget.thresholds: expected a list"},
        BadValue{"FeatureBudget.factors", "FeatureBudget.factors: [ 1.0, 1.3 ]",
                 "FeatureBudget.factors: must have one more entry than FeatureBudget.thresholds"},
        BadValue{"Output.trajectory_format", "Output.trajectory_format: \"ply\"",
                 "Output.trajectory_format: must be"}));

TEST(SettingsErrors, PartialRectificationNamesTheMissingKey) {
  TempDir dir;
  std::string text = test::read_text(config("EuRoC.yaml"));
  const std::regex right_p("\nRIGHT\\.P:[^\n]*\n(   [^\n]*\n){4}");
  ASSERT_TRUE(std::regex_search(text, right_p));
  write_text(dir / "s.yaml", std::regex_replace(text, right_p, "\n"));
  const auto message = error_of([&] { (void)load_settings((dir / "s.yaml").string(), SensorKind::kStereo); });
  EXPECT_NE(message.find("RIGHT.P: missing"), std::string::npos) << message;
}

TEST(SettingsErrors, CameraMustMatchRectifiedProjection) {
  TempDir dir;
  Settings s = load_settings(config("EuRoC.yaml"), SensorKind::kStereo);
  s.camera.fx = 458.654;  // the raw focal length instead of the rectified one
  write_settings((dir / "s.yaml").string(), s);
  const auto message = error_of([&] { (void)load_settings((dir / "s.yaml").string(), SensorKind::kStereo); });
  EXPECT_NE(message.find("Camera.fx"), std::string::npos) << message;
  EXPECT_NE(message.find("LEFT.P"), std::string::npos) << message;
}

}  // namespace
}  // namespace crowdslam::io
