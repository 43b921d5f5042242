#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "test_support.h"

namespace {

using crowdslam::test::run_cli;
using crowdslam::test::shared_data;

// Number of non-empty lines.
int line_count(const std::string& text) {
  int lines = 0;
  bool content = false;
  for (const char ch : text) {
    if (ch == '\n') {
      lines += content ? 1 : 0;
      content = false;
    } else {
      content = true;
    }
  }
  return lines + (content ? 1 : 0);
}

TEST(CliDataset, BonnInfoJsonHasTheReadmeCounts) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const auto r = run_cli({"dataset", "info", shared_data("bonn_crowd").string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["layout"], "tum");
  EXPECT_EQ(j["sensor"], "rgbd");
  EXPECT_EQ(j["colour_frames"], 928);  // README: 928 colour, 927 depth, 933 poses, 31 s, 640x480
  EXPECT_EQ(j["depth_frames"], 927);
  EXPECT_EQ(j["ground_truth_poses"], 933);
  const int pairs = j["frames"];
  EXPECT_GT(pairs, 900);  // nearly every depth map has a colour image within 20 ms
  EXPECT_LE(pairs, 927);
  EXPECT_NEAR(j["duration_s"].get<double>(), 31.0, 0.5);
  EXPECT_NEAR(j["last_timestamp_s"].get<double>() - j["first_timestamp_s"].get<double>(),
              j["duration_s"].get<double>(), 1e-9);
  EXPECT_EQ(j["width"], 640);
  EXPECT_EQ(j["height"], 480);
  EXPECT_EQ(j["depth_type"], "16UC1");
}

TEST(CliDataset, BonnInfoTextNamesTheCounts) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const auto r = run_cli({"dataset", "info", shared_data("bonn_crowd").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("928"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("927"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("933 poses"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("640x480"), std::string::npos) << r.out;
}

TEST(CliDataset, EurocInfoHasNinetyFiveStereoPairs) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  const auto r = run_cli({"--json", "dataset", "info", shared_data("euroc_v101_micro").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["layout"], "euroc");
  EXPECT_EQ(j["sensor"], "stereo");
  EXPECT_EQ(j["frames"], 95);
  EXPECT_EQ(j["ground_truth_poses"], 84);
  EXPECT_EQ(j["width"], 752);
  EXPECT_EQ(j["height"], 480);
  EXPECT_NEAR(j["duration_s"].get<double>(), 94 / 20.0, 1e-3);  // 95 frames at 20 Hz
}

TEST(CliDataset, CheckReadsEveryEurocFrame) {
  CROWDSLAM_REQUIRE_SHARED("euroc_v101_micro");
  const auto r = run_cli({"--json", "dataset", "info", "--check", shared_data("euroc_v101_micro").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["checked_frames"], 95);
}

TEST(CliDataset, CheckFindsATruncatedDepthMapThatInfoAloneDoesNotRead) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  // Two real Bonn frames copied into a temporary TUM layout; the second depth map is cut in half.
  namespace fs = std::filesystem;
  crowdslam::test::TempDir dir;
  const fs::path cut = crowdslam::test::copy_two_bonn_frames(dir.path()).depth[1];
  fs::resize_file(cut, fs::file_size(cut) / 2);

  const auto info = run_cli({"dataset", "info", dir.path().string(), "--json"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["frames"], 2);
  const auto checked = run_cli({"dataset", "info", dir.path().string(), "--check"});
  EXPECT_EQ(checked.exit_code, 1);
  EXPECT_EQ(line_count(checked.err), 1) << checked.err;
  EXPECT_NE(checked.err.find(cut.string()), std::string::npos) << checked.err;
}

TEST(CliDataset, MissingDirectoryIsOneErrorLineNamingIt) {
  const std::string path = "/nonexistent/crowdslam/dataset";
  const auto r = run_cli({"dataset", "info", path});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("error: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(path), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST(CliDataset, UnknownLayoutIsAnErrorNamingTheDirectory) {
  crowdslam::test::TempDir dir;
  crowdslam::test::write_text(dir / "notes.txt", "no dataset here\n");
  const auto r = run_cli({"dataset", "info", dir.path().string(), "--json"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(dir.path().string()), std::string::npos) << r.err;
}

TEST(CliDataset, BrokenListNamesFileAndLine) {
  crowdslam::test::TempDir dir;
  crowdslam::test::write_text(dir / "rgb.txt", "# colour\n0.0\n");
  const auto r = run_cli({"dataset", "info", dir.path().string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("rgb.txt:2:"), std::string::npos) << r.err;
}

TEST(CliDataset, InfoNeedsASource) {
  const auto r = run_cli({"dataset", "info"});
  EXPECT_NE(r.exit_code, 0);
}

}  // namespace
