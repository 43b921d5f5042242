// `crowdslam run --save-map` and `crowdslam map info|export` (issue 12): a map from an interrupted run is a
// valid map, info reports it, the exports are well-formed (binary PLY with one vertex per map point).
#include <gtest/gtest.h>

#include <csignal>
#include <fstream>

#include "run_test_helpers.h"

using namespace crowdslam::test;

namespace {
// The PLY header's vertex count and the header's length.
std::pair<size_t, size_t> ply_vertices(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  size_t vertices = 0;
  size_t header_bytes = 0;
  while (std::getline(in, line)) {
    header_bytes += line.size() + 1;
    if (line.rfind("element vertex ", 0) == 0) vertices = std::stoul(line.substr(15));
    if (line == "end_header") break;
  }
  return {vertices, header_bytes};
}
}  // namespace

TEST(CliMap, InterruptedRunSavesAValidMapThatInfoAndExportRead) {
  TempDir dir;
  const auto dataset = synth_small(dir, 200);
  const auto out = dir / "out";
  const auto map_file = dir / "room.db";
  CliProcess child({"run", "--dataset", dataset.string(), "--out", out.string(), "--save-map", map_file.string()});
  ASSERT_TRUE(child.wait_until(
      [&] { return std::filesystem::exists(out / "CameraTrajectory.txt") && trajectory_lines(out / "CameraTrajectory.txt").size() >= 60; },
      300))
      << child.current_stderr();
  child.send_signal(SIGINT);
  const auto result = child.wait(60);
  ASSERT_EQ(result.exit_code, 130) << result.err;
  const auto doc = read_json(out / "run.json");
  EXPECT_EQ(doc["end_state"], "interrupted");
  ASSERT_TRUE(doc["map"]["saved"].is_object()) << doc["map"].dump();
  EXPECT_TRUE(temporaries(dir.path()).empty());

  const auto info = run_cli({"--json", "map", "info", map_file.string()});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto i = nlohmann::json::parse(info.out);
  EXPECT_EQ(i["origin"]["end_state"], "interrupted");
  EXPECT_EQ(i["sensor"], "rgbd");
  EXPECT_EQ(i["keyframes"], doc["map"]["saved"]["keyframes"]);
  EXPECT_GT(i["map_points"].get<size_t>(), 100u);
  EXPECT_GT(i["observations"].get<size_t>(), i["map_points"].get<size_t>());

  const auto ply = dir / "points.ply";
  const auto kf_ply = dir / "keyframes.ply";
  const auto tum = dir / "keyframes.txt";
  const auto exported = run_cli({"map", "export", map_file.string(), "--ply", ply.string(), "--keyframes",
                                 kf_ply.string(), "--trajectory", tum.string()});
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const auto [points, header] = ply_vertices(ply);
  EXPECT_EQ(points, i["map_points"].get<size_t>());
  EXPECT_EQ(std::filesystem::file_size(ply), header + points * 16);  // 3 float + 1 uint per vertex
  const auto [keyframes, kf_header] = ply_vertices(kf_ply);
  EXPECT_EQ(keyframes, i["keyframes"].get<size_t>());
  EXPECT_EQ(std::filesystem::file_size(kf_ply), kf_header + keyframes * 12);
  EXPECT_EQ(trajectory_lines(tum).size(), keyframes);
}

TEST(CliMap, BadMapFilesAndOptionsExitOneWithTheFileNamed) {
  TempDir dir;
  const auto junk = dir / "junk.db";
  std::ofstream(junk) << "not a database";
  const auto info = run_cli({"map", "info", junk.string()});
  EXPECT_EQ(info.exit_code, 1);
  EXPECT_NE(info.err.find("junk.db"), std::string::npos) << info.err;
  const auto missing = run_cli({"map", "export", (dir / "absent.db").string(), "--ply", (dir / "p.ply").string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("absent.db"), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "p.ply"));
  const auto nothing = run_cli({"map", "export", junk.string()});
  EXPECT_EQ(nothing.exit_code, 1);
  // map optimise: a bad input or option names it and writes nothing.
  const auto optimised = dir / "optimised.db";
  const auto bad_input = run_cli({"map", "optimise", junk.string(), "--out", optimised.string()});
  EXPECT_EQ(bad_input.exit_code, 1);
  EXPECT_NE(bad_input.err.find("junk.db"), std::string::npos) << bad_input.err;
  const auto bad_iterations =
      run_cli({"map", "optimise", junk.string(), "--out", optimised.string(), "--iterations", "0"});
  EXPECT_EQ(bad_iterations.exit_code, 1);
  EXPECT_NE(bad_iterations.err.find("--iterations"), std::string::npos) << bad_iterations.err;
  const auto bad_ground = run_cli({"map", "optimise", junk.string(), "--out", optimised.string(), "--ground", "-0.5"});
  EXPECT_EQ(bad_ground.exit_code, 1);
  EXPECT_NE(bad_ground.err.find("--ground"), std::string::npos) << bad_ground.err;
  EXPECT_FALSE(std::filesystem::exists(optimised));
  EXPECT_TRUE(temporaries(dir.path()).empty());
  const auto dataset = synth_small(dir, 5);
  const auto localization = run_cli({"run", "--dataset", dataset.string(), "--out", (dir / "o").string(), "--localization"});
  EXPECT_EQ(localization.exit_code, 1);
  EXPECT_NE(localization.err.find("--load-map"), std::string::npos) << localization.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o"));
}
