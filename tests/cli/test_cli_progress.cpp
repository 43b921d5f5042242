// Progress of the long commands (issue 13): with stderr not a terminal (a pipe here), `run`, `detect` and
// `vocab train` and `synth` print plain progress lines (done/total, rate) every tenth of the work and a last one at
// the end, never redrawn in place; -q silences them. (On a terminal the same line is redrawn in place:
// tests/util/test_progress.cpp covers ProgressLine itself.)
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "test_support.h"

namespace {
namespace fs = std::filesystem;
using crowdslam::test::run_cli;
using crowdslam::test::TempDir;

// A 30-frame synthetic RGB-D sequence with people, shared by the tests of this file.
class CliProgress : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const auto r = run_cli({"-q", "synth", "--out", sequence().string(), "--frames", "30", "--width", "320",
                            "--height", "240", "--people", "2"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path sequence() { return *dir_ / "seq"; }
  static fs::path path(const std::string& name) { return *dir_ / name; }

  // The command's stderr without and with -q (both runs must succeed).
  static std::pair<std::string, std::string> stderr_plain_and_quiet(const std::vector<std::string>& plain_args,
                                                                    const std::vector<std::string>& quiet_args) {
    const auto plain = run_cli(plain_args);
    EXPECT_EQ(plain.exit_code, 0) << plain.err;
    std::vector<std::string> quiet = {"-q"};
    quiet.insert(quiet.end(), quiet_args.begin(), quiet_args.end());
    const auto silent = run_cli(quiet);
    EXPECT_EQ(silent.exit_code, 0) << silent.err;
    return {plain.err, silent.err};
  }

  static TempDir* dir_;
};
TempDir* CliProgress::dir_ = nullptr;

size_t matches(const std::string& text, const std::string& pattern) {
  const std::regex re(pattern);
  return static_cast<size_t>(std::distance(std::sregex_iterator(text.begin(), text.end(), re), std::sregex_iterator()));
}

// Plain lines at 3, 6, ..., 30 of 30 (a tenth of the total), with the rate; none redrawn in place.
void expect_plain_lines(const std::string& err, const std::string& unit) {
  EXPECT_EQ(err.find('\r'), std::string::npos) << err;
  EXPECT_NE(err.find(unit + " 3/30 (10 %)  "), std::string::npos) << err;
  EXPECT_NE(err.find(unit + " 30/30 (100 %)  "), std::string::npos) << err;
  EXPECT_EQ(matches(err, unit + " [0-9]+/30 \\("), 10u) << err;
  EXPECT_GE(matches(err, unit + " [0-9]+/30 \\([0-9]+ %\\)  [0-9.]+ " + unit + "s/s"), 9u) << err;
}
}  // namespace

TEST_F(CliProgress, RunPrintsPlainLinesAndQuietSilencesThem) {
  const auto [err, quiet] = stderr_plain_and_quiet(
      {"run", "--dataset", sequence().string(), "--out", path("run").string()},
      {"run", "--dataset", sequence().string(), "--out", path("run_quiet").string()});
  expect_plain_lines(err, "frame");
  EXPECT_NE(err.find("tracked "), std::string::npos) << err;  // the detail: state, tracked, keyframes, ...
  EXPECT_EQ(matches(quiet, "frame [0-9]+/30"), 0u) << quiet;
}

TEST_F(CliProgress, DetectPrintsPlainLinesAndQuietSilencesThem) {
  if (!fs::exists(crowdslam::test::shared_dir() / "models" / "yolo-fastest-1.1" / "yolo-fastest-1.1_body.cfg"))
    GTEST_SKIP() << "shared models missing";
  const std::vector<std::string> args = {"detect", "--dataset", sequence().string(), "--model", "body", "--input", "160"};
  auto plain = args, quiet = args;
  plain.insert(plain.end(), {"--out", path("det.txt").string()});
  quiet.insert(quiet.end(), {"--out", path("det_quiet.txt").string()});
  const auto [err, silent] = stderr_plain_and_quiet(plain, quiet);
  expect_plain_lines(err, "frame");
  EXPECT_NE(err.find("boxes "), std::string::npos) << err;
  EXPECT_EQ(matches(silent, "frame [0-9]+/30"), 0u) << silent;
}

TEST_F(CliProgress, VocabTrainPrintsPlainLinesForReadingAndEveryLevelAndQuietSilencesThem) {
  const std::vector<std::string> args = {"vocab", "train", "--k", "4", "--levels", "2", "--features", "300"};
  auto plain = args, quiet = args;
  plain.insert(plain.end(), {"--out", path("plain.voc").string(), sequence().string()});
  quiet.insert(quiet.end(), {"--out", path("quiet.voc").string(), sequence().string()});
  const auto [err, silent] = stderr_plain_and_quiet(plain, quiet);
  expect_plain_lines(err, "image");
  // k-means: each level's progress in descriptors, ending at 100 %.
  EXPECT_EQ(matches(err, "descriptor [0-9]+/[0-9]+ \\(100 %\\)[^\n]*k-means level 1/2"), 1u) << err;
  EXPECT_EQ(matches(err, "descriptor [0-9]+/[0-9]+ \\(100 %\\)[^\n]*k-means level 2/2"), 1u) << err;
  EXPECT_EQ(matches(silent, "image [0-9]+/30|descriptor [0-9]+/"), 0u) << silent;
}

TEST_F(CliProgress, SynthPrintsPlainLinesAndQuietSilencesThem) {
  const std::vector<std::string> args = {"synth", "--frames", "30", "--width", "160", "--height", "120"};
  auto plain = args, quiet = args;
  plain.insert(plain.end(), {"--out", path("synth_plain").string()});
  quiet.insert(quiet.end(), {"--out", path("synth_quiet").string()});
  const auto [err, silent] = stderr_plain_and_quiet(plain, quiet);
  expect_plain_lines(err, "frame");
  EXPECT_EQ(matches(silent, "frame [0-9]+/30"), 0u) << silent;
  EXPECT_TRUE(fs::exists(path("synth_quiet") / "rgb" / "000029.png"));
}
