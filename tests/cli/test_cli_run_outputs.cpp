// `crowdslam run` keeps its work and says how it ended (issue 10): an unreadable frame mid-sequence
// (finding 2), map resets (3), --out checked up front and never mixing two runs (4), --json on stdout
// only (5), --save-frames streamed (13), temporaries of a killed run (14), runs that track nothing (11).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "run_test_helpers.h"

using namespace crowdslam::test;
namespace fs = std::filesystem;

namespace {
std::vector<std::string> run_args(const fs::path& seq, const fs::path& out, std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

void blacken(const fs::path& seq, int first, int last) {
  const cv::Mat black(240, 320, CV_8UC3, cv::Scalar(0, 0, 0));
  for (int i = first; i <= last; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    ASSERT_TRUE(cv::imwrite((seq / "rgb" / name).string(), black));
  }
}
}  // namespace

TEST(CliRunOutputs, UnreadableFrameMidSequenceKeepsTheFramesTrackedBeforeIt) {
  TempDir dir;
  const auto seq = synth_small(dir, 40);
  fs::resize_file(seq / "rgb" / "000025.png", fs::file_size(seq / "rgb" / "000025.png") / 2);
  const auto out = dir / "out";
  const auto r = run_cli(run_args(seq, out, {"--sequential"}));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("000025.png"), std::string::npos) << r.err;
  // One error line, the last one, naming the file and where the outputs are (warnings may precede it).
  const auto last_line = r.err.substr(r.err.rfind('\n', r.err.size() - 2) + 1);
  EXPECT_EQ(last_line.rfind("error: ", 0), 0u) << r.err;
  EXPECT_NE(last_line.find("000025.png"), std::string::npos) << r.err;
  EXPECT_NE(last_line.find(out.string()), std::string::npos) << r.err;
  size_t errors = 0;
  for (size_t pos = r.err.find("error: "); pos != std::string::npos; pos = r.err.find("error: ", pos + 1)) ++errors;
  EXPECT_EQ(errors, 1u) << r.err;
  const auto doc = read_json(out / "run.json");
  EXPECT_EQ(doc["end_state"].get<std::string>().rfind("failed: ", 0), 0u) << doc["end_state"];
  EXPECT_NE(doc["end_state"].get<std::string>().find("000025.png"), std::string::npos);
  EXPECT_EQ(doc["summary"]["frames"], 25);
  const auto lines = trajectory_lines(out / "CameraTrajectory.txt");
  EXPECT_EQ(lines.size(), doc["summary"]["tracked_frames"].get<size_t>());
  EXPECT_GE(lines.size(), 24u);
  EXPECT_TRUE(temporaries(out).empty());
}

TEST(CliRunOutputs, SkipBadFramesCountsAndWarnsAndGoesOn) {
  TempDir dir;
  const auto seq = synth_small(dir, 40);
  fs::resize_file(seq / "rgb" / "000025.png", fs::file_size(seq / "rgb" / "000025.png") / 2);
  const auto out = dir / "out";
  const auto r = run_cli(run_args(seq, out, {"--sequential", "--skip-bad-frames"}));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("000025.png"), std::string::npos) << r.err;
  const auto doc = read_json(out / "run.json");
  EXPECT_EQ(doc["end_state"], "completed");
  EXPECT_EQ(doc["input"]["skipped_frames"], 1);
  EXPECT_EQ(doc["summary"]["frames"], 39);
}

TEST(CliRunOutputs, MapResetKeepsEveryTrackedFrameAndListsTheSegments) {
  TempDir dir;
  const auto seq = synth_small(dir, 60);
  blacken(seq, 4, 9);  // tracking is lost with few keyframes: the map is reset, a new one is built
  const auto out = dir / "out";
  const auto r = run_cli(run_args(seq, out, {"--sequential"}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = read_json(out / "run.json");
  ASSERT_GE(doc["segments"].size(), 2u) << doc["segments"].dump();
  EXPECT_GE(doc["summary"]["map_resets"].get<int>(), 1);
  size_t tracked_in_segments = 0;
  for (const auto& s : doc["segments"]) tracked_in_segments += s["tracked"].get<size_t>();
  const auto lines = trajectory_lines(out / "CameraTrajectory.txt");
  EXPECT_EQ(lines.size(), doc["summary"]["tracked_frames"].get<size_t>());
  EXPECT_EQ(lines.size(), tracked_in_segments);
  EXPECT_GE(doc["segments"][0]["tracked"].get<size_t>(), 3u);  // the frames before the reset are kept
  EXPECT_EQ(lines.front().substr(0, 8), "1.000000");             // frame 0 among them
  EXPECT_GE(lines.size(), 40u);
  // Accuracy per segment, the summary's figure from the longest one.
  const auto& accuracy = doc["accuracy"];
  ASSERT_TRUE(accuracy.is_object());
  EXPECT_EQ(accuracy["evaluated"], "longest map segment");
  EXPECT_GE(accuracy["segments"].size(), 2u);
  size_t longest = 0;
  for (const auto& s : doc["segments"]) longest = std::max(longest, s["tracked"].get<size_t>());
  EXPECT_EQ(accuracy["poses"].get<size_t>(), longest);
  EXPECT_LT(accuracy["ate_rmse_m"].get<double>(), 0.1);
  // The featureless frames were warned about.
  EXPECT_NE(r.err.find("ORB keypoints"), std::string::npos) << r.err;
  EXPECT_EQ(doc["input"]["featureless_frames"], 6);
}

TEST(CliRunOutputs, RunThatTracksNothingFailsUnlessAllowed) {
  TempDir dir;
  const auto seq = synth_small(dir, 8);
  blacken(seq, 0, 7);
  const auto r = run_cli(run_args(seq, dir / "out", {"--sequential"}));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no frame was tracked"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--allow-untracked"), std::string::npos) << r.err;
  EXPECT_EQ(read_json(dir / "out" / "run.json")["end_state"], "failed: no frame was tracked (0 of 8)");
  const auto allowed = run_cli(run_args(seq, dir / "out2", {"--sequential", "--allow-untracked"}));
  EXPECT_EQ(allowed.exit_code, 0) << allowed.err;
  EXPECT_EQ(read_json(dir / "out2" / "run.json")["end_state"], "completed");
}

TEST(CliRunOutputs, BadOutIsAnErrorBeforeAnyFrame) {
  TempDir dir;
  const auto seq = synth_small(dir, 8);
  write_text(dir / "a_file", "x");
  for (const auto& bad : {dir / "a_file", dir / "a_file" / "sub", fs::path("/proc/crowdslam_no_such_dir/out")}) {
    SCOPED_TRACE(bad.string());
    const auto r = run_cli(run_args(seq, bad));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.find("frame"), std::string::npos) << "failed after running: " << r.err;
  }
  if (::geteuid() != 0) {  // root ignores permissions
    fs::create_directory(dir / "readonly");
    fs::permissions(dir / "readonly", fs::perms::owner_read | fs::perms::owner_exec);
    const auto r = run_cli(run_args(seq, dir / "readonly" / "out"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("readonly"), std::string::npos) << r.err;
    fs::permissions(dir / "readonly", fs::perms::owner_all);
  }
}

TEST(CliRunOutputs, FullDiskMidRunLeavesAMarkedPartialRunWithCompleteLines) {
  TempDir dir;
  const auto seq = synth_small(dir, 120);
  const auto out = dir / "out";
  // Files may not grow beyond 4 kB: run.json's header fits, the trajectory journal overflows mid-run.
  CliProcess child(run_args(seq, out, {"--sequential"}), ChildLimits{4096});
  const auto r = child.wait(120);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("CameraTrajectory.txt"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("File too large"), std::string::npos) << r.err;
  const auto doc = read_json(out / "run.json");  // still valid: the "running" header or the failed state
  EXPECT_NE(doc["end_state"], "completed");
  for (const auto& line : trajectory_lines(out / "CameraTrajectory.txt")) EXPECT_EQ(count_fields(line), 8u) << line;
  EXPECT_FALSE(trajectory_lines(out / "CameraTrajectory.txt").empty());
  EXPECT_TRUE(temporaries(out).empty());
}

TEST(CliRunOutputs, EarlierRunIsRefusedOrReplacedNeverMixed) {
  TempDir dir;
  const auto seq = synth_small(dir, 12);
  const auto out = dir / "out";
  ASSERT_EQ(run_cli(run_args(seq, out, {"--save-frames", "5"})).exit_code, 0);
  ASSERT_TRUE(fs::exists(out / "frames" / "000005.jpg"));
  // Again without --overwrite: refused, the earlier run untouched.
  const auto before = read_text(out / "run.json");
  const auto refused = run_cli(run_args(seq, out));
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("--overwrite"), std::string::npos) << refused.err;
  EXPECT_EQ(read_text(out / "run.json"), before);
  // A stale temporary of a killed run, then --overwrite without --save-frames: nothing of the old run stays.
  write_text(out / "CameraTrajectory.txt.tmp.99999", "partial");
  const auto replaced = run_cli(run_args(seq, out, {"--overwrite"}));
  EXPECT_EQ(replaced.exit_code, 0) << replaced.err;
  EXPECT_FALSE(fs::exists(out / "frames"));
  EXPECT_TRUE(temporaries(out).empty());
  EXPECT_NE(read_text(out / "run.json"), before);
  // A directory with someone else's files is never touched.
  write_text(dir / "mine" / "notes.txt", "keep");
  const auto foreign = run_cli(run_args(seq, dir / "mine", {"--overwrite"}));
  EXPECT_EQ(foreign.exit_code, 1);
  EXPECT_NE(foreign.err.find("notes.txt"), std::string::npos) << foreign.err;
  EXPECT_EQ(read_text(dir / "mine" / "notes.txt"), "keep");
}

TEST(CliRunOutputs, JsonPrintsExactlyOneDocumentOnStdout) {
  TempDir dir;
  const auto seq = synth_small(dir, 12);
  for (const bool quiet : {false, true}) {
    std::vector<std::string> args = {"--json", "run", "--dataset", seq.string(), "--out",
                                     (dir / (quiet ? "q" : "v")).string(), "--no-people-filter"};
    if (quiet) args.insert(args.begin(), "-q");
    const auto r = run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto doc = nlohmann::json::parse(r.out);  // throws on anything else on stdout
    EXPECT_EQ(doc["end_state"], "completed");
    EXPECT_EQ(doc["summary"]["frames"], 12);
  }
  // An error: still one document, naming it.
  const auto r = run_cli({"--json", "run", "--dataset", (dir / "missing").string(), "--out", (dir / "e").string()});
  EXPECT_EQ(r.exit_code, 1);
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["exit_code"], 1);
  EXPECT_NE(doc["error"].get<std::string>().find("missing"), std::string::npos);
}

TEST(CliRunOutputs, SavedFramesAreWrittenWhileTheRunGoesOn) {
  TempDir dir;
  const auto seq = synth_small(dir, 300);
  const auto out = dir / "out";
  CliProcess child(run_args(seq, out, {"--save-frames", "1"}));
  bool seen_while_running = false;
  child.wait_until(
      [&] {
        if (fs::exists(out / "frames" / "000010.jpg") && !fs::exists(out / "KeyFrameTrajectory.txt")) seen_while_running = true;
        return seen_while_running;
      },
      120);
  const auto r = child.wait(120);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(seen_while_running);
  size_t jpegs = 0;
  for (const auto& e : fs::directory_iterator(out / "frames")) jpegs += e.path().extension() == ".jpg";
  EXPECT_EQ(jpegs, 300u);
  const cv::Mat frame = cv::imread((out / "frames" / "000299.jpg").string());
  EXPECT_EQ(frame.cols, 320);
}

// OpenCV's imgcodecs and videoio (and the 200 libraries behind them) are loaded only when needed
// (io/opencv_extras.h): a run on PNG / JPEG images, with saved frames and the report, needs none of them.
TEST(CliRunOutputs, RunOnPngAndJpegImagesNeedsNoneOfOpenCvsCodecs) {
  TempDir dir;
  const auto seq = synth_small(dir, 40);  // the generator writes its PNGs through the module
  const std::string missing = (dir / "no-such-module.so").string();
  ASSERT_EQ(setenv("CROWDSLAM_OPENCV_EXTRAS", missing.c_str(), 1), 0);  // inherited by the runs below
  const auto out = dir / "out";
  const auto r = run_cli(run_args(seq, out, {"--save-frames", "10"}));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat frame = cv::imread((out / "frames" / "000030.jpg").string());
  EXPECT_EQ(frame.cols, 320);
  EXPECT_EQ(frame.rows, 240);
  EXPECT_NE(read_text(out / "report.html").find("data:image/jpeg;base64,/9j/"), std::string::npos);
  // A video does need the module: the error says which file could not be loaded.
  write_text(dir / "clip.avi", std::string("RIFF\x10\0\0\0AVI LIST\0\0\0\0\xff\xfe", 22));
  const auto video = run_cli({"run", "--dataset", (dir / "clip.avi").string(), "--out", (dir / "v").string()});
  unsetenv("CROWDSLAM_OPENCV_EXTRAS");
  EXPECT_NE(video.exit_code, 0);
  EXPECT_NE(video.err.find(missing), std::string::npos) << video.err;
}

TEST(CliRunOutputs, DepthImagesWithoutAnyDepthAreWarnedAndCounted) {
  TempDir dir;
  const auto seq = synth_small(dir, 10);
  const cv::Mat zero(240, 320, CV_16UC1, cv::Scalar(0));
  for (int i = 3; i <= 6; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    ASSERT_TRUE(cv::imwrite((seq / "depth" / name).string(), zero));
  }
  const auto out = dir / "out";
  const auto r = run_cli(run_args(seq, out, {"--sequential"}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("depth/000003.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("without any valid depth"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("4 frames had no valid depth"), std::string::npos) << r.err;
  const auto doc = read_json(out / "run.json");
  EXPECT_EQ(doc["input"]["empty_depth_frames"], 4);
}
