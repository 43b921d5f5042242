// DnnDetector with the YOLOX backend on the shared ONNX models (YOLOX-nano COCO, ByteTrack-nano), the model
// zoo and the settings -> detector mapping. Forward tests skip when the models are not there.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "crowdslam/people/detection_metrics.h"
#include "crowdslam/people/detector_setup.h"
#include "crowdslam/people/dnn_detector.h"
#include "crowdslam/people/mot_format.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {
namespace fs = std::filesystem;

ModelFiles shared_model(const std::string& name) {
  ModelFiles m = resolve_model(name);
  const ZooModel* zoo = find_zoo_model(name);
  m.config = (test::shared_dir() / "models" / zoo->folder / zoo->config).string();
  return m;
}

#define REQUIRE_MODEL(name)                                                                                  \
  do {                                                                                                      \
    if (!fs::exists(shared_model(name).config))                                                            \
      GTEST_SKIP() << "model " << name << " missing (" << shared_model(name).config                          \
                   << "): see scripts/install_models.sh";                                                  \
  } while (0)

struct FrameResult {
  DetectionCounts counts;
  std::size_t ground_truth = 0;
};

// Detections on frame `frame` of a shared MOT sequence against its ground truth (IoU >= 0.5).
FrameResult evaluate_on(DnnDetector& detector, const std::string& sequence, int frame) {
  const fs::path seq = test::shared_data("mot") / sequence;
  char name[16];
  std::snprintf(name, sizeof(name), "%06d.jpg", frame);
  const cv::Mat image = cv::imread((seq / "img1" / name).string());
  EXPECT_FALSE(image.empty());
  const Detections det = detector.detect(image, static_cast<std::size_t>(frame - 1));
  std::vector<cv::Rect2f> gt, found;
  for (const MotRow& row : read_mot_file((seq / "gt" / "gt.txt").string(), true).rows)
    if (row.frame == frame && row.score != 0) gt.push_back(row.box);
  for (const PersonBox& b : det.boxes) {
    EXPECT_GE(b.box.x, 0);
    EXPECT_GE(b.box.y, 0);
    EXPECT_LE(b.box.x + b.box.width, image.cols + 1e-3);
    EXPECT_LE(b.box.y + b.box.height, image.rows + 1e-3);
    found.push_back(b.box);
  }
  FrameResult r;
  evaluate_frame(gt, {}, found, 0.5, r.counts);
  r.ground_truth = gt.size();
  return r;
}

DetectorOptions options(cv::Size input, double confidence, double nms) {
  DetectorOptions o;
  o.input_width = input.width;
  o.input_height = input.height;
  o.confidence = confidence;
  o.nms = nms;
  return o;
}

TEST(ModelZoo, NamesResolveToFilesBackendAndPreprocessing) {
  const ModelFiles yolox = resolve_model("yolox");
  EXPECT_EQ(fs::path(yolox.config).filename(), "yolox_nano.onnx");
  EXPECT_EQ(fs::path(yolox.config).parent_path().filename(), "yolox-nano");
  EXPECT_TRUE(yolox.weights.empty());
  EXPECT_EQ(yolox.backend, Backend::kYolox);
  EXPECT_EQ(resolved_preprocess(yolox), "yolox");
  const ModelFiles bytetrack = resolve_model("bytetrack");
  EXPECT_EQ(fs::path(bytetrack.config).filename(), "bytetrack_nano.onnx");
  EXPECT_EQ(resolved_preprocess(bytetrack), "bytetrack");
  EXPECT_EQ(resolved_backend(resolve_model("body")), Backend::kDarknet);
  // Paths: by extension, unless a backend is given.
  EXPECT_EQ(resolved_backend(resolve_model("/x/net.onnx")), Backend::kYoloOnnx);
  EXPECT_EQ(resolved_backend(resolve_model("/x/net.cfg")), Backend::kDarknet);
  EXPECT_EQ(zoo_model_names(), "body, coco, yolox, bytetrack");
  const std::string unknown = test::error_of([] { (void)resolve_model("yolov8"); });
  EXPECT_NE(unknown.find("'yolov8'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("bytetrack"), std::string::npos) << unknown;
  EXPECT_NE(test::error_of([] { (void)parse_backend("onnx"); }).find("Detector.backend"), std::string::npos);
}

// A model folder missing from $CROWDSLAM_MODELS (an older install with only Yolo-Fastest) is found in the
// next model directory that has it.
TEST(ModelZoo, EachModelFolderIsLookedUpInTurn) {
  test::TempDir dir;
  fs::create_directories(dir / "yolo-fastest-1.1");
  ::setenv("CROWDSLAM_MODELS", dir.path().c_str(), 1);
  const ModelFiles body = resolve_model("body");
  const ModelFiles yolox = resolve_model("yolox");
  ::unsetenv("CROWDSLAM_MODELS");
  EXPECT_EQ(fs::path(body.config).parent_path(), dir / "yolo-fastest-1.1");
  EXPECT_NE(fs::path(yolox.config).parent_path(), dir / "yolox-nano");
  EXPECT_EQ(fs::path(yolox.config).parent_path().filename(), "yolox-nano");
}

TEST(DetectorSetup, SettingsKeysReachModelAndOptions) {
  io::DetectorSettings d;  // the defaults of every config/*.yaml: body, 160, stretch
  DetectorSetup s = detector_setup(d);
  EXPECT_EQ(s.model.name, "body");
  EXPECT_EQ(s.options.input(), cv::Size(160, 160));
  EXPECT_FALSE(s.options.resize.has_value());
  EXPECT_DOUBLE_EQ(s.options.confidence, 0.2);
  EXPECT_DOUBLE_EQ(s.options.nms, 0.1);
  d.model_cfg = "/m/custom.onnx";
  d.backend = "yolox";
  d.preprocess = "bytetrack";
  d.input_width = 416;
  d.input_height = 256;
  d.resize = "stretch";
  d.person_class = 2;
  d.confidence = 0.3;
  s = detector_setup(d);
  EXPECT_EQ(s.model.config, "/m/custom.onnx");
  EXPECT_EQ(resolved_backend(s.model), Backend::kYolox);
  EXPECT_EQ(resolved_preprocess(s.model), "bytetrack");
  EXPECT_EQ(s.options.input(), cv::Size(416, 256));
  EXPECT_EQ(s.options.resize, ResizeMode::kStretch);
  EXPECT_EQ(s.options.person_class, 2);
  EXPECT_DOUBLE_EQ(s.options.confidence, 0.3);
  // --detector overrides Detector.model_cfg; a zoo model keeps its own person class.
  s = detector_setup(d, "yolox");
  EXPECT_EQ(fs::path(s.model.config).filename(), "yolox_nano.onnx");
  EXPECT_EQ(s.options.person_class, 0);
}

TEST(OnnxDetector, YoloxOutputLayoutIsTheRawHead) {
  REQUIRE_MODEL("yolox");
  DnnDetector d(shared_model("yolox"), options({416, 256}, 0.3, 0.45));
  EXPECT_EQ(d.name(), "yolox_nano@416x256");
  EXPECT_EQ(d.backend(), Backend::kYolox);
  const std::vector<cv::Mat> out = d.forward_raw(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(90)));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(shape_text(out[0]), "1x2184x85");
  // Objectness and class scores come out of a sigmoid (in [0, 1]); xy / wh are raw (some negative).
  const cv::Mat table(2184, 85, CV_32F, const_cast<float*>(out[0].ptr<float>()));
  double lo = 0, hi = 0;
  cv::minMaxLoc(table.colRange(4, 85), &lo, &hi);
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.0);
  cv::minMaxLoc(table.colRange(0, 2), &lo, &hi);
  EXPECT_LT(lo, 0.0);
}

// Real forward passes on MOT frames: most annotated people found (IoU >= 0.5), few false boxes.
TEST(OnnxDetector, YoloxAndByteTrackFindAnnotatedPeople) {
  CROWDSLAM_REQUIRE_SHARED("mot");
  REQUIRE_MODEL("yolox");
  REQUIRE_MODEL("bytetrack");
  for (const char* name : {"yolox", "bytetrack"}) {
    DnnDetector d(shared_model(name), options({416, 320}, 0.3, 0.45));
    for (const auto& [sequence, frame] : {std::pair{"TUD-Stadtmitte", 1}, std::pair{"PETS09-S2L1-first150", 41}}) {
      const FrameResult r = evaluate_on(d, sequence, frame);
      ASSERT_GE(r.ground_truth, 4u);
      EXPECT_GE(r.counts.recall(), 0.6) << name << " " << sequence << ": TP " << r.counts.true_positives
                                        << " of " << r.ground_truth;
      EXPECT_GE(r.counts.precision(), 0.6) << name << " " << sequence << ": FP " << r.counts.false_positives;
    }
  }
}

// The letterbox must not shift boxes: the same frame at two input aspects gives boxes that agree
// (a wrong unmapping, e.g. dividing by the input size instead of the resized area, moves them by 20 %).
TEST(OnnxDetector, BoxesAgreeAcrossInputAspects) {
  CROWDSLAM_REQUIRE_SHARED("mot");
  REQUIRE_MODEL("yolox");
  const cv::Mat image = cv::imread((test::shared_data("mot") / "TUD-Stadtmitte" / "img1" / "000001.jpg").string());
  DnnDetector wide(shared_model("yolox"), options({512, 288}, 0.4, 0.45));
  DnnDetector square(shared_model("yolox"), options({416, 416}, 0.4, 0.45));
  const Detections a = wide.detect(image, 0);
  const Detections b = square.detect(image, 0);
  ASSERT_GE(a.boxes.size(), 3u);
  int matched = 0;
  for (const PersonBox& x : a.boxes)
    for (const PersonBox& y : b.boxes)
      if (box_iou(x.box, y.box) >= 0.7) ++matched;
  EXPECT_GE(matched, static_cast<int>(a.boxes.size()) - 1);
}

TEST(OnnxDetector, ErrorsNameTheFile) {
  REQUIRE_MODEL("bytetrack");
  // A one-class model with person class 1, found at the warm-up in the constructor.
  DetectorOptions o = options({320, 192}, 0.3, 0.45);
  o.person_class = 1;
  const std::string cls = test::error_of([&] { DnnDetector d(shared_model("bytetrack"), o); });
  EXPECT_NE(cls.find("bytetrack_nano.onnx"), std::string::npos) << cls;
  EXPECT_NE(cls.find("person class 1"), std::string::npos) << cls;
  // A Darknet cfg declared as a YOLOX model.
  ModelFiles cfg = resolve_model("body");
  cfg.config = (test::shared_dir() / "models" / "yolo-fastest-1.1" / "yolo-fastest-1.1_body.cfg").string();
  cfg.backend = Backend::kYolox;
  const std::string wrong = test::error_of([&] { DnnDetector d(cfg, o); });
  EXPECT_NE(wrong.find("yolo-fastest-1.1_body.cfg"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("yolox"), std::string::npos) << wrong;
}

}  // namespace
}  // namespace crowdslam::people
