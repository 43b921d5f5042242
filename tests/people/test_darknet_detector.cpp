// DarknetDetector on the shared Yolo-Fastest models, and its error paths.
#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <opencv2/imgcodecs.hpp>

#include "crowdslam/people/darknet_detector.h"
#include "crowdslam/people/detection_metrics.h"
#include "crowdslam/people/mot_format.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {
namespace fs = std::filesystem;

fs::path model_dir() { return test::shared_dir() / "models" / "yolo-fastest-1.1"; }

ModelFiles files(const std::string& config, const std::string& weights) {
  ModelFiles m;
  m.config = config;
  m.weights = weights;
  return m;
}
ModelFiles body_model() {
  return files((model_dir() / "yolo-fastest-1.1_body.cfg").string(),
               (model_dir() / "yolo-fastest-1.1_body.weights").string());
}
ModelFiles coco_model() {
  return files((model_dir() / "yolo-fastest-1.1.cfg").string(), (model_dir() / "yolo-fastest-1.1.weights").string());
}

#define REQUIRE_MODELS()                                                                    \
  do {                                                                                      \
    if (!fs::exists(model_dir())) GTEST_SKIP() << "shared models missing: " << model_dir(); \
  } while (0)

std::string load_error(const ModelFiles& model) {
  try {
    DarknetDetector d(model, {});
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DarknetDetector, MissingModelNamesTheFile) {
  test::TempDir dir;
  const std::string cfg = (dir / "nothing.cfg").string();
  EXPECT_NE(load_error(files(cfg, (dir / "nothing.weights").string())).find("nothing.cfg"), std::string::npos);
  test::write_text(dir / "only.cfg", "[net]\n");
  EXPECT_NE(
      load_error(files((dir / "only.cfg").string(), (dir / "only.weights").string())).find("only.weights"),
      std::string::npos);
}

TEST(DarknetDetector, CorruptModelIsOneInputErrorNamingTheFile) {
  REQUIRE_MODELS();
  test::TempDir dir;
  // A cfg that is not a network, with real weights.
  test::write_text(dir / "garbage.cfg", "this is not a darknet cfg\n[convolutional]\nfilters=abc\n");
  const std::string garbage = load_error(files((dir / "garbage.cfg").string(), body_model().weights));
  EXPECT_NE(garbage.find("garbage.cfg"), std::string::npos) << garbage;
  // Real cfg, truncated weights.
  const std::string weights = (dir / "cut.weights").string();
  fs::copy_file(body_model().weights, weights);
  fs::resize_file(weights, fs::file_size(weights) / 3);
  const std::string cut = load_error(files(body_model().config, weights));
  EXPECT_NE(cut.find("cut.weights"), std::string::npos) << cut;
  // Empty weights.
  test::write_text(dir / "empty.weights", "");
  const std::string empty = load_error(files(body_model().config, (dir / "empty.weights").string()));
  EXPECT_NE(empty.find("empty.weights"), std::string::npos) << empty;
}

TEST(DarknetDetector, OnnxErrorsNameTheFile) {
  test::TempDir dir;
  EXPECT_NE(load_error(files((dir / "yolo.onnx").string(), "")).find("yolo.onnx"), std::string::npos);
  test::write_text(dir / "bad.onnx", "not a protobuf at all");
  const std::string bad = load_error(files((dir / "bad.onnx").string(), ""));
  EXPECT_NE(bad.find("bad.onnx"), std::string::npos) << bad;
}

TEST(DarknetDetector, PersonClassOutOfRangeIsAnError) {
  REQUIRE_MODELS();
  DetectorOptions options;
  options.person_class = 3;  // the body model has one class
  // Found by the warm-up forward pass in the constructor, before the first frame.
  const std::string message = test::error_of([&] { DarknetDetector d(body_model(), options); });
  EXPECT_NE(message.find("yolo-fastest-1.1_body.cfg"), std::string::npos) << message;
  EXPECT_NE(message.find("person class 3"), std::string::npos) << message;
}

// OpenCV's region layer multiplies objectness into the class scores: no class score exceeds its row's
// objectness, and on a frame with people some scores are strictly between 0 and objectness.
TEST(DarknetDetector, ClassScoresAlreadyIncludeObjectness) {
  REQUIRE_MODELS();
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat image =
      cv::imread((test::shared_data("bonn_crowd") / "rgb" / "1548339829.89644.jpg").string());
  ASSERT_FALSE(image.empty());
  for (const ModelFiles& model : {body_model(), coco_model()}) {
    DarknetDetector d(model, {});
    int rows = 0, confident = 0;
    for (const cv::Mat& out : d.forward_raw(image)) {
      for (int r = 0; r < out.rows; ++r, ++rows) {
        const float* row = out.ptr<float>(r);
        for (int c = 5; c < out.cols; ++c) ASSERT_LE(row[c], row[4] + 1e-6f) << model.config;
        if (row[5] > 0.2f) ++confident;
      }
    }
    EXPECT_GT(rows, 100);
    EXPECT_GT(confident, 0) << model.config;
  }
}

// On TUD-Campus frame 1 the body model at 320 finds most annotated people (IoU >= 0.5), every box lies in
// the image, and NMS keeps a subset of the raw boxes.
TEST(DarknetDetector, FindsAnnotatedPeopleOnMotFrame) {
  REQUIRE_MODELS();
  CROWDSLAM_REQUIRE_SHARED("mot");
  const fs::path seq = test::shared_data("mot") / "TUD-Campus";
  const cv::Mat image = cv::imread((seq / "img1" / "000001.jpg").string());
  ASSERT_FALSE(image.empty());
  DetectorOptions options;
  options.input_size = 320;
  DarknetDetector d(body_model(), options);
  const Detections det = d.detect(image, 0);
  EXPECT_GT(det.time_ms, 0.0);
  EXPECT_LE(det.boxes.size(), det.raw.size());
  for (const PersonBox& b : det.raw) {
    EXPECT_GE(b.box.x, 0);
    EXPECT_GE(b.box.y, 0);
    EXPECT_LE(b.box.x + b.box.width, image.cols + 1e-3);
    EXPECT_LE(b.box.y + b.box.height, image.rows + 1e-3);
    EXPECT_GE(b.confidence, 0.2f);
  }
  std::vector<cv::Rect2f> gt, found;
  for (const MotRow& row : read_mot_file((seq / "gt" / "gt.txt").string(), true).rows)
    if (row.frame == 1 && row.score != 0) gt.push_back(row.box);
  for (const PersonBox& b : det.boxes) found.push_back(b.box);
  DetectionCounts counts;
  evaluate_frame(gt, {}, found, 0.5, counts);
  ASSERT_GE(gt.size(), 4u);
  EXPECT_GE(counts.recall(), 0.5) << "TP " << counts.true_positives << " of " << gt.size();
  EXPECT_GE(counts.precision(), 0.5) << "FP " << counts.false_positives;
}

// OpenCV's region layer has its own score threshold (0.2 by default); a lower confidence threshold must
// still reach boxes between it and 0.2.
TEST(DarknetDetector, ConfidenceBelowPointTwoTakesEffect) {
  REQUIRE_MODELS();
  CROWDSLAM_REQUIRE_SHARED("mot");
  const cv::Mat image =
      cv::imread((test::shared_data("mot") / "TUD-Campus" / "img1" / "000001.jpg").string());
  DetectorOptions low;
  low.input_size = 320;
  low.confidence = 0.05;
  DarknetDetector d(body_model(), low);
  int below = 0;
  for (const PersonBox& b : d.detect(image, 0).raw) {
    EXPECT_GE(b.confidence, 0.05f);
    if (b.confidence < 0.2f) ++below;
  }
  EXPECT_GT(below, 0);
}

// Aspect-true inputs for the Darknet backend: a non-square stretch (320 x 256 for a 4:3 frame) and the
// letterbox both find the annotated people, with boxes mapped back into the 640 x 480 image.
TEST(DarknetDetector, NonSquareAndLetterboxInputs) {
  REQUIRE_MODELS();
  CROWDSLAM_REQUIRE_SHARED("mot");
  const fs::path seq = test::shared_data("mot") / "TUD-Stadtmitte";
  const cv::Mat image = cv::imread((seq / "img1" / "000001.jpg").string());
  std::vector<cv::Rect2f> gt;
  for (const MotRow& row : read_mot_file((seq / "gt" / "gt.txt").string(), true).rows)
    if (row.frame == 1 && row.score != 0) gt.push_back(row.box);
  for (const std::optional<ResizeMode> resize : {std::optional<ResizeMode>(), std::optional(ResizeMode::kLetterbox)}) {
    DetectorOptions options;
    options.input_width = 320;
    options.input_height = 256;
    options.resize = resize;
    DarknetDetector d(body_model(), options);
    EXPECT_EQ(d.name(), "yolo-fastest-1.1_body@320x256");
    EXPECT_EQ(d.preprocessing().resize, resize.value_or(ResizeMode::kStretch));
    std::vector<cv::Rect2f> found;
    for (const PersonBox& b : d.detect(image, 0).boxes) {
      EXPECT_LE(b.box.y + b.box.height, image.rows + 1e-3);
      found.push_back(b.box);
    }
    DetectionCounts counts;
    evaluate_frame(gt, {}, found, 0.5, counts);
    EXPECT_GE(counts.recall(), 0.5) << to_string(d.preprocessing().resize) << ": TP " << counts.true_positives
                                    << " of " << gt.size();
  }
}

}  // namespace
}  // namespace crowdslam::people
