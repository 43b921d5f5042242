#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <regex>
#include <string>

#include "test_support.h"

using crowdslam::test::run_cli;

namespace {
// stdout of a shell command (empty when it fails).
std::string command_output(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
  if (::pclose(pipe) != 0) return {};
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}
}  // namespace

TEST(Cli, VersionPrintsTheProjectVersionAndTheBuiltCommit) {
  const auto r = run_cli({"--version"});
  EXPECT_EQ(r.exit_code, 0);
  std::smatch m;
  ASSERT_TRUE(std::regex_match(r.out, m, std::regex(R"(crowdslam (\S+) \(git ([0-9a-f]{12}(-dirty)?|unknown)\)\n)")))
      << r.out;
  EXPECT_EQ(m[1].str(), CROWDSLAM_EXPECTED_VERSION);
  // Built from a git checkout: the commit is the checkout's HEAD (the build re-reads it at every build).
  const std::string source = crowdslam::test::source_dir().string();
  const std::string head = command_output("git -C '" + source + "' rev-parse --short=12 HEAD 2>/dev/null");
  if (!head.empty()) {
    EXPECT_EQ(m[2].str().substr(0, 12), head) << r.out;
  }
}

TEST(Cli, ChangelogStartsWithTheVersionThatIsBuilt) {
  std::ifstream changelog(crowdslam::test::source_dir() / "CHANGELOG.md");
  ASSERT_TRUE(changelog.good());
  const std::regex heading(R"(## \[?(\d+\.\d+\.\d+)\]?.*)");
  std::string line;
  std::smatch m;
  while (std::getline(changelog, line) && !std::regex_match(line, m, heading)) {
  }
  ASSERT_FALSE(m.empty()) << "no '## [X.Y.Z]' heading in CHANGELOG.md";
  EXPECT_EQ(m[1].str(), CROWDSLAM_EXPECTED_VERSION);
}

TEST(Cli, NoSubcommandIsAnError) {
  const auto r = run_cli({});
  EXPECT_NE(r.exit_code, 0);
}

TEST(Cli, UnknownSubcommandIsAnError) {
  const auto r = run_cli({"frobnicate"});
  EXPECT_NE(r.exit_code, 0);
}
