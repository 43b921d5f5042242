// `crowdslam detect` and `crowdslam detect-eval`: output formats, closed-form metrics, errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "crowdslam/util/text.h"
#include "test_support.h"

using crowdslam::test::run_cli;
using crowdslam::test::TempDir;
using crowdslam::test::write_text;

namespace {
namespace fs = std::filesystem;

bool models_available() {
  return fs::exists(crowdslam::test::shared_dir() / "models" / "yolo-fastest-1.1" /
                    "yolo-fastest-1.1_body.cfg");
}

TEST(CliDetectEval, ClosedFormCaseHumanAndJson) {
  TempDir dir;
  // gt: two people; det: one with IoU 0.8 with the first, one false.
  write_text(dir / "gt.txt", "1,1,0,0,100,100,1,-1,-1,-1\n1,2,300,300,50,100,1,-1,-1,-1\n");
  write_text(dir / "det.txt", "1,-1,0,0,100,80,0.9,-1,-1,-1\n1,-1,500,0,50,100,0.8,-1,-1,-1\n");
  const auto human =
      run_cli({"detect-eval", "--gt", (dir / "gt.txt").string(), "--det", (dir / "det.txt").string()});
  ASSERT_EQ(human.exit_code, 0) << human.err;
  EXPECT_NE(human.out.find("TP 1  FP 1  FN 1"), std::string::npos) << human.out;
  EXPECT_NE(human.out.find("MODP           80.0 %"), std::string::npos) << human.out;
  const auto json = run_cli(
      {"--json", "detect-eval", "--gt", (dir / "gt.txt").string(), "--det", (dir / "det.txt").string()});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["tp"], 1);
  EXPECT_EQ(j["fp"], 1);
  EXPECT_EQ(j["fn"], 1);
  EXPECT_DOUBLE_EQ(j["precision"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["recall"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["moda"].get<double>(), 0.0);
  EXPECT_NEAR(j["modp"].get<double>(), 0.8, 1e-6);
  EXPECT_EQ(j["ground_truth_format"], "mot15");
  // A stricter IoU threshold turns the match into a miss plus a false positive.
  const auto strict = run_cli({"--json", "detect-eval", "--gt", (dir / "gt.txt").string(), "--det",
                               (dir / "det.txt").string(), "--iou", "0.85"});
  ASSERT_EQ(strict.exit_code, 0) << strict.err;
  const auto s = nlohmann::json::parse(strict.out);
  EXPECT_EQ(s["tp"], 0);
  EXPECT_DOUBLE_EQ(s["moda"].get<double>(), -1.0);
  EXPECT_TRUE(s["modp"].is_null());
}

TEST(CliDetectEval, MinVisibilityOnMot17GroundTruth) {
  TempDir dir;
  write_text(dir / "gt.txt", "1,1,0,0,10,10,1,1,0.9\n1,2,100,0,10,10,1,1,0.2\n");
  write_text(dir / "det.txt", "1,-1,0,0,10,10,1\n");
  const auto all = run_cli(
      {"--json", "detect-eval", "--gt", (dir / "gt.txt").string(), "--det", (dir / "det.txt").string()});
  ASSERT_EQ(all.exit_code, 0) << all.err;
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(all.out)["recall"].get<double>(), 0.5);
  const auto half = run_cli({"--json", "detect-eval", "--gt", (dir / "gt.txt").string(), "--det",
                             (dir / "det.txt").string(), "--min-visibility", "0.5"});
  ASSERT_EQ(half.exit_code, 0) << half.err;
  const auto j = nlohmann::json::parse(half.out);
  EXPECT_DOUBLE_EQ(j["recall"].get<double>(), 1.0);
  EXPECT_EQ(j["ignored_ground_truth_boxes"], 1);
  EXPECT_EQ(j["ground_truth_format"], "mot16");
}

TEST(CliDetectEval, BadInputIsOneErrorLineNamingFileAndLine) {
  TempDir dir;
  write_text(dir / "gt.txt", "1,1,0,0,10,10,1,-1,-1,-1\n");
  write_text(dir / "det.txt", "1,-1,0,0,10,10,1\n1,-1,0,0,10,nan,1\n");
  const auto r =
      run_cli({"detect-eval", "--gt", (dir / "gt.txt").string(), "--det", (dir / "det.txt").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("error: "), std::string::npos);
  EXPECT_NE(r.err.find("det.txt:2"), std::string::npos) << r.err;
  const auto missing =
      run_cli({"detect-eval", "--gt", (dir / "nope.txt").string(), "--det", (dir / "det.txt").string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("nope.txt"), std::string::npos) << missing.err;
}

TEST(CliDetect, MissingModelAndBadOptionsFailWithoutOutput) {
  CROWDSLAM_REQUIRE_SHARED("mot");
  TempDir dir;
  const std::string seq = (crowdslam::test::shared_data("mot") / "TUD-Campus").string();
  const std::string out = (dir / "det.txt").string();
  const auto r =
      run_cli({"detect", "--dataset", seq, "--out", out, "--model", (dir / "absent.cfg").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("absent.cfg"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  const auto size = run_cli({"detect", "--dataset", seq, "--out", out, "--input-size", "100"});
  EXPECT_EQ(size.exit_code, 1);
  EXPECT_NE(size.err.find("input_size"), std::string::npos) << size.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliDetect, MotSequenceRoundTripThroughDetectEval) {
  CROWDSLAM_REQUIRE_SHARED("mot");
  if (!models_available()) GTEST_SKIP() << "shared models missing";
  TempDir dir;
  const fs::path seq = crowdslam::test::shared_data("mot") / "TUD-Campus";
  const std::string out = (dir / "det.txt").string();
  // The paper's setting (body @ 160, 0.2 / 0.1), which the SLAM default uses.
  const std::vector<std::string> paper = {"--model", "body", "--input", "160", "--confidence", "0.2", "--nms", "0.1"};
  std::vector<std::string> args = {"--json", "detect", "--dataset", seq.string(), "--out", out};
  args.insert(args.end(), paper.begin(), paper.end());
  const auto r = run_cli(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frames"], 71);
  // Every row: 10 fields, frame in 1..71 (sequence numbering), box inside the 640x480 image, conf >= 0.2.
  std::size_t rows = 0;
  for (const std::string& line : crowdslam::read_lines(out)) {
    const auto f = crowdslam::split_fields(line);
    ASSERT_EQ(f.size(), 10u) << line;
    const int frame = std::stoi(f[0]);
    EXPECT_GE(frame, 1);
    EXPECT_LE(frame, 71);
    EXPECT_EQ(f[1], "-1");
    EXPECT_GE(std::stod(f[2]), 0.0);
    EXPECT_LE(std::stod(f[2]) + std::stod(f[4]), 640.0 + 1e-3);
    EXPECT_LE(std::stod(f[3]) + std::stod(f[5]), 480.0 + 1e-3);
    EXPECT_GE(std::stod(f[6]), 0.2);
    ++rows;
  }
  EXPECT_EQ(rows, j["boxes"].get<std::size_t>());
  // Against the ground truth the detector finds most people with few false boxes.
  const auto e = run_cli({"--json", "detect-eval", "--gt", (seq / "gt" / "gt.txt").string(), "--det", out});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const auto m = nlohmann::json::parse(e.out);
  EXPECT_GT(m["recall"].get<double>(), 0.5);
  EXPECT_GT(m["precision"].get<double>(), 0.7);
  // Before NMS there are at least as many boxes.
  const std::string raw = (dir / "raw.txt").string();
  std::vector<std::string> raw_args = {"--json", "detect", "--dataset", seq.string(), "--out", raw, "--raw"};
  raw_args.insert(raw_args.end(), paper.begin(), paper.end());
  const auto rr = run_cli(raw_args);
  ASSERT_EQ(rr.exit_code, 0) << rr.err;
  EXPECT_GE(nlohmann::json::parse(rr.out)["boxes"].get<std::size_t>(), rows);
}

// --input W x H and the per-model defaults: what was used is in the JSON; bad sizes and conflicting options
// fail before any output.
TEST(CliDetect, InputSizesBackendsAndDefaults) {
  CROWDSLAM_REQUIRE_SHARED("mot");
  TempDir dir;
  const std::string seq = (crowdslam::test::shared_data("mot") / "TUD-Stadtmitte").string();
  const std::string out = (dir / "det.txt").string();
  for (const char* bad : {"416x250", "0x256", "wide"}) {
    const auto r = run_cli({"detect", "--dataset", seq, "--out", out, "--model", "body", "--input", bad});
    EXPECT_EQ(r.exit_code, 1) << bad;
    EXPECT_NE(r.err.find("--input"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
  }
  const auto both = run_cli({"detect", "--dataset", seq, "--out", out, "--input", "320", "--input-size", "320"});
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_NE(both.err.find("--input-size"), std::string::npos) << both.err;
  const auto unknown = run_cli({"detect", "--dataset", seq, "--out", out, "--model", "yolov8"});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.err.find("yolov8"), std::string::npos) << unknown.err;
  EXPECT_FALSE(fs::exists(out));
  if (!models_available()) GTEST_SKIP() << "shared models missing";
  const auto body = run_cli({"--json", "detect", "--dataset", seq, "--out", out, "--model", "body", "--input",
                             "320x256", "--resize", "letterbox", "--max-frames", "2"});
  ASSERT_EQ(body.exit_code, 0) << body.err;
  const auto b = nlohmann::json::parse(body.out);
  EXPECT_EQ(b["input_width"], 320);
  EXPECT_EQ(b["input_height"], 256);
  EXPECT_EQ(b["backend"], "darknet");
  EXPECT_EQ(b["resize"], "letterbox");
  EXPECT_EQ(b["detector"], "yolo-fastest-1.1_body@320x256");
  const fs::path yolox = crowdslam::test::shared_dir() / "models" / "yolox-nano" / "yolox_nano.onnx";
  if (!fs::exists(yolox)) GTEST_SKIP() << "YOLOX model missing: " << yolox;
  // Without --settings and --input: the default model with its own default input and thresholds.
  const auto d = run_cli({"--json", "detect", "--dataset", seq, "--out", out, "--max-frames", "2"});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const auto j = nlohmann::json::parse(d.out);
  EXPECT_EQ(j["detector"], "yolox_nano@320x256");
  EXPECT_EQ(j["resize"], "letterbox");
  EXPECT_DOUBLE_EQ(j["confidence"].get<double>(), 0.3);
  EXPECT_DOUBLE_EQ(j["nms"].get<double>(), 0.45);
  EXPECT_GE(j["boxes"].get<int>(), 8);  // 7 annotated people a frame
  // A YOLOX .onnx given as a path needs --backend yolox; as yolo-onnx it runs (same row width) but
  // decodes the raw head as if it were decoded, which the layout cannot tell: the backend is declared.
  const auto path = run_cli({"--json", "detect", "--dataset", seq, "--out", out, "--model", yolox.string(),
                             "--backend", "yolox", "--preprocess", "yolox", "--input", "416x320", "--max-frames", "1"});
  ASSERT_EQ(path.exit_code, 0) << path.err;
  EXPECT_EQ(nlohmann::json::parse(path.out)["backend"], "yolox");
  // With --settings, the SLAM detector: body @ 160 (stretch), 0.2 / 0.1, boxes before NMS.
  const auto slam = run_cli({"--json", "detect", "--settings", (crowdslam::test::source_dir() / "config" / "Bonn.yaml").string(),
                             "--dataset", seq, "--out", out, "--max-frames", "1"});
  ASSERT_EQ(slam.exit_code, 0) << slam.err;
  const auto sj = nlohmann::json::parse(slam.out);
  EXPECT_EQ(sj["detector"], "yolo-fastest-1.1_body@160");
  EXPECT_EQ(sj["resize"], "stretch");
  EXPECT_DOUBLE_EQ(sj["nms"].get<double>(), 0.1);
  EXPECT_EQ(sj["before_nms"], true);
}

}  // namespace
