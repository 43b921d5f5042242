// --out rules: new or empty directories are used, an earlier run needs overwrite (and is then removed
// completely), foreign files and non-directories are refused, nothing is touched by a refusal.
#include <gtest/gtest.h>

#include <filesystem>

#include "crowdslam/journal/output_dir.h"
#include "test_support.h"

using crowdslam::journal::check_output_dir;
using crowdslam::journal::is_run_output_name;
using crowdslam::journal::prepare_output_dir;
using crowdslam::test::error_of;
using crowdslam::test::TempDir;
using crowdslam::test::write_text;
namespace fs = std::filesystem;

TEST(OutputDir, KnowsItsOwnNamesAndTheirTemporaries) {
  EXPECT_TRUE(is_run_output_name("run.json"));
  EXPECT_TRUE(is_run_output_name("CameraTrajectory.txt"));
  EXPECT_TRUE(is_run_output_name("frames"));
  EXPECT_TRUE(is_run_output_name("run.json.tmp.1234"));
  EXPECT_FALSE(is_run_output_name("run.json.tmp.12a4"));
  EXPECT_FALSE(is_run_output_name("notes.txt.tmp.1234"));
  EXPECT_FALSE(is_run_output_name("notes.txt"));
}

TEST(OutputDir, NewNestedDirectoryIsCreated) {
  TempDir dir;
  EXPECT_NO_THROW(check_output_dir(dir / "a" / "b", false));
  EXPECT_FALSE(fs::exists(dir / "a"));  // the check has no side effects
  prepare_output_dir(dir / "a" / "b", false);
  EXPECT_TRUE(fs::is_directory(dir / "a" / "b"));
  EXPECT_TRUE(fs::is_empty(dir / "a" / "b"));  // the write probe is gone
}

TEST(OutputDir, EarlierRunNeedsOverwriteAndIsThenRemovedCompletely) {
  TempDir dir;
  const auto out = dir / "out";
  write_text(out / "run.json", "{}");
  write_text(out / "frames" / "000000.jpg", "x");
  write_text(out / "KeyFrameTrajectory.txt.tmp.42", "x");
  const auto refused = error_of([&] { prepare_output_dir(out, false); });
  EXPECT_NE(refused.find("--overwrite"), std::string::npos) << refused;
  EXPECT_TRUE(fs::exists(out / "frames" / "000000.jpg"));
  const auto removed = prepare_output_dir(out, true);
  EXPECT_EQ(removed.size(), 3u);
  EXPECT_TRUE(fs::is_empty(out));
}

TEST(OutputDir, ForeignFilesAndFilesAreRefusedEvenWithOverwrite) {
  TempDir dir;
  write_text(dir / "home" / "thesis.tex", "precious");
  write_text(dir / "home" / "run.json", "{}");
  const auto foreign = error_of([&] { prepare_output_dir(dir / "home", true); });
  EXPECT_NE(foreign.find("thesis.tex"), std::string::npos) << foreign;
  EXPECT_TRUE(fs::exists(dir / "home" / "run.json"));
  write_text(dir / "file", "x");
  EXPECT_NE(error_of([&] { check_output_dir(dir / "file", true); }).find("not a directory"), std::string::npos);
  EXPECT_NE(error_of([&] { check_output_dir(dir / "file" / "sub", true); }).find("not a directory"), std::string::npos);
  EXPECT_NE(error_of([&] { check_output_dir("", false); }).find("--out"), std::string::npos);
}
