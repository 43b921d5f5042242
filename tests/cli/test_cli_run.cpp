// `crowdslam run` error paths found before the first frame: an unsupported sensor, bad settings. Each
// gives one line on stderr naming the file or option, a non-zero exit, and no output. (A bad frame in
// the middle of a sequence keeps the frames before it: test_cli_run_outputs.cpp.)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "test_support.h"

using crowdslam::test::run_cli;
using crowdslam::test::TempDir;

namespace {
std::filesystem::path small_sequence(const TempDir& dir) {
  const auto seq = dir / "seq";
  const auto r = run_cli({"-q", "synth", "--out", seq.string(), "--frames", "12", "--width", "320", "--height", "240"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return seq;
}
}  // namespace

TEST(CliRun, UnsupportedSensorAndBadSettingsAreClearErrors) {
  TempDir dir;
  const auto seq = small_sequence(dir);
  const auto out = dir / "out";
  const auto unknown = run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--sensor", "lidar"});
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.err.find("--sensor"), std::string::npos) << unknown.err;
  EXPECT_NE(unknown.err.find("lidar"), std::string::npos) << unknown.err;

  // A settings file with a bad value names the file and the key.
  std::ifstream in(seq / "settings.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto pos = text.find("Camera.fx:");
  ASSERT_NE(pos, std::string::npos);
  text.replace(pos, text.find('\n', pos) - pos, "Camera.fx: -5.0");
  crowdslam::test::write_text(dir / "bad.yaml", text);
  const auto bad = run_cli({"-q", "run", "--dataset", seq.string(), "--settings", (dir / "bad.yaml").string(), "--out",
                            out.string()});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("bad.yaml"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("Camera.fx"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}
