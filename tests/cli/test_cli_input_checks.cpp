// Bad input through the command line (issue 10): one clear error line naming the file (exit 1) or a
// CLI11 range error, never a crash, a raw filesystem error (exit 2) or a silent success.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test_support.h"

namespace {

namespace fs = std::filesystem;
using crowdslam::test::run_cli;
using crowdslam::test::shared_data;
using crowdslam::test::TempDir;
using crowdslam::test::write_text;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

int line_count(const std::string& text) {
  int lines = 0;
  for (std::size_t start = 0; start < text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    if (end > start) ++lines;
    start = end + 1;
  }
  return lines;
}

// A two-frame TUM layout with synthetic images.
void make_tum(const fs::path& dir) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  for (int i = 0; i < 2; ++i) {
    cv::imwrite((dir / "rgb" / (std::to_string(i) + ".png")).string(),
                cv::Mat(6, 8, CV_8UC3, cv::Scalar(i, 2, 3)));
    cv::imwrite((dir / "depth" / (std::to_string(i) + ".png")).string(),
                cv::Mat(6, 8, CV_16UC1, cv::Scalar(1000)));
  }
  write_text(dir / "rgb.txt", "0.0 rgb/0.png\n1.0 rgb/1.png\n");
  write_text(dir / "depth.txt", "0.0 depth/0.png\n1.0 depth/1.png\n");
}

std::vector<char> bytes_of(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(CliInput, ListFileGivenAsTheDatasetAsksForTheDirectory) {
  TempDir dir;
  make_tum(dir.path());
  const std::string list = (dir / "rgb.txt").string();
  const auto r = run_cli({"dataset", "info", list});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_TRUE(contains(r.err, "error: " + list + ": is a list file")) << r.err;
  EXPECT_TRUE(contains(r.err, "pass the dataset directory (its parent, " + dir.path().string())) << r.err;
  EXPECT_EQ(run_cli({"dataset", "info", dir.path().string()}).exit_code, 0);
}

TEST(CliInput, CheckFailsOnACutBonnJpegThatStillEndsWithTheEndMarker) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  TempDir dir;
  const fs::path second = crowdslam::test::copy_two_bonn_frames(dir.path()).colour[1];
  std::vector<char> jpeg = bytes_of(second);
  jpeg.resize(jpeg.size() / 2);
  jpeg.push_back(static_cast<char>(0xFF));
  jpeg.push_back(static_cast<char>(0xD9));
  write_bytes(second, jpeg);
  const auto r = run_cli({"dataset", "info", "--check", dir.path().string()});
  EXPECT_EQ(r.exit_code, 1);  // used to pass: libjpeg printed a warning naming no file
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_TRUE(contains(r.err, "error: " + second.string() + ": corrupt JPEG image: Corrupt JPEG data"))
      << r.err;
}

TEST(CliInput, CheckFailsOnFlippedBitsInABonnJpeg) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  TempDir dir;
  const fs::path second = crowdslam::test::copy_two_bonn_frames(dir.path()).colour[1];
  std::vector<char> jpeg = bytes_of(second);
  // 64 bytes: a single flipped bit often decodes without complaint (JPEG has no checksum).
  for (std::size_t i = jpeg.size() / 2; i < jpeg.size() / 2 + 64; ++i)
    jpeg[i] = static_cast<char>(jpeg[i] ^ 0x5A);
  write_bytes(second, jpeg);
  const auto r = run_cli({"dataset", "info", "--check", dir.path().string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_TRUE(contains(r.err, "error: " + second.string() + ": corrupt JPEG image")) << r.err;
}

TEST(CliInput, InfoWithoutAnyColourDepthPairFailsNamingBothLists) {
  TempDir dir;
  make_tum(dir.path());
  write_text(dir / "depth.txt", "50.0 depth/0.png\n51.0 depth/1.png\n");
  const auto r = run_cli({"dataset", "info", dir.path().string()});
  EXPECT_EQ(r.exit_code, 1);  // used to print "frames: 0" and exit 0
  EXPECT_TRUE(contains(r.err, (dir / "rgb.txt").string() + ": no colour image has a depth map in " +
                                  (dir / "depth.txt").string()))
      << r.err;
}

TEST(CliInput, NameTooLongIsAnInputErrorNamingListAndLine) {
  TempDir dir;
  make_tum(dir.path());
  write_text(dir / "rgb.txt", "0.0 rgb/0.png\n1.0 rgb/" + std::string(100000, 'y') + ".png\n");
  const auto r = run_cli({"dataset", "info", dir.path().string()});
  EXPECT_EQ(r.exit_code, 1);  // used to be a raw filesystem_error, exit 2
  EXPECT_EQ(line_count(r.err), 1);
  EXPECT_TRUE(contains(r.err, (dir / "rgb.txt").string() + ":2: listed image")) << r.err.substr(0, 500);
  EXPECT_TRUE(contains(r.err, "File name too long")) << r.err.substr(0, 500);
  EXPECT_LT(r.err.size(), 1000u);
}

TEST(CliInput, DetectThreadsOutOfRangeIsAClearErrorNotACrash) {
  TempDir dir;
  make_tum(dir.path());
  const auto r = run_cli({"detect", "--dataset", dir.path().string(), "--out", (dir / "det.txt").string(),
                          "--threads", "100000"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_LT(r.exit_code, 128) << "killed by a signal";  // it used to segfault at exit
  EXPECT_TRUE(contains(r.err, "--threads")) << r.err;
  EXPECT_TRUE(contains(r.err, "not in range")) << r.err;
  EXPECT_FALSE(fs::exists(dir / "det.txt"));
}

TEST(CliInput, DetectNumericOptionsAreBounded) {
  TempDir dir;
  make_tum(dir.path());
  const std::vector<std::pair<std::string, std::string>> bad = {{"--max-frames", "-1"},
                                                                {"--input-size", "320000"},
                                                                {"--confidence", "7"},
                                                                {"--nms", "-0.5"},
                                                                {"--person-class", "-3"}};
  for (const auto& [option, value] : bad) {
    SCOPED_TRACE(option);
    const auto r = run_cli(
        {"detect", "--dataset", dir.path().string(), "--out", (dir / "det.txt").string(), option, value});
    EXPECT_NE(r.exit_code, 0);
    EXPECT_LT(r.exit_code, 128);
    EXPECT_TRUE(contains(r.err, option)) << r.err;
    EXPECT_FALSE(fs::exists(dir / "det.txt"));
  }
  const auto fps = run_cli({"dataset", "info", dir.path().string(), "--fps", "1e300"});
  EXPECT_NE(fps.exit_code, 0);
  EXPECT_TRUE(contains(fps.err, "--fps")) << fps.err;
}

TEST(CliInput, DetectEvalWarnsAboutSkippedBoxesWithFileAndLine) {
  TempDir dir;
  write_text(dir / "gt.txt", "1,1,0,0,100,100,1,-1,-1,-1\n");
  const std::string det = (dir / "det.txt").string();
  write_text(det, "1,-1,0,0,100,100,0.9,-1,-1,-1\n1,-1,5,5,-10,10,0.9,-1,-1,-1\n");
  const auto r = run_cli({"--json", "detect-eval", "--gt", (dir / "gt.txt").string(), "--det", det});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out + r.err, det + ":2: 1 box skipped")) << r.out << r.err;
}

bool has_warning(const crowdslam::test::CliResult& r) {
  return contains(r.out + r.err, "[warning]") || contains(r.out + r.err, "warning:");
}

TEST(CliInput, SharedDatasetsOpenAndCheckWithoutWarnings) {
  for (const char* name : {"bonn_crowd", "euroc_v101_micro", "kitti07_head"}) {
    if (!crowdslam::test::shared_available(name)) continue;
    SCOPED_TRACE(name);
    const auto r = run_cli({"dataset", "info", shared_data(name).string()});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_FALSE(has_warning(r)) << r.out << r.err;
  }
  if (!crowdslam::test::shared_available("euroc_v101_micro")) GTEST_SKIP() << "no euroc_v101_micro";
  // --check decodes every frame with the strict decoders: the real data must pass.
  const auto checked =
      run_cli({"--json", "dataset", "info", "--check", shared_data("euroc_v101_micro").string()});
  ASSERT_EQ(checked.exit_code, 0) << checked.err;
  EXPECT_FALSE(has_warning(checked)) << checked.err;
}

TEST(CliInput, SharedMotFilesEvaluateWithoutWarnings) {
  for (const char* name : {"mot/TUD-Campus", "mot/TUD-Stadtmitte", "mot/PETS09-S2L1-first150"}) {
    if (!crowdslam::test::shared_available(name)) continue;
    SCOPED_TRACE(name);
    const fs::path seq = shared_data(name);
    const auto r = run_cli({"--json", "detect-eval", "--gt", (seq / "gt/gt.txt").string(), "--det",
                            (seq / "det/det.txt").string()});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_FALSE(has_warning(r)) << r.err;
  }
}

}  // namespace
