#include <gtest/gtest.h>

#include "test_support.h"

using crowdslam::test::run_cli;

TEST(Cli, VersionPrintsVersionAndExitsZero) {
  const auto r = run_cli({"--version"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("crowdslam"), std::string::npos);
}

TEST(Cli, NoSubcommandIsAnError) {
  const auto r = run_cli({});
  EXPECT_NE(r.exit_code, 0);
}

TEST(Cli, UnknownSubcommandIsAnError) {
  const auto r = run_cli({"frobnicate"});
  EXPECT_NE(r.exit_code, 0);
}
