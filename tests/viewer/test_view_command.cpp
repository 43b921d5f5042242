// `crowdslam view` (issue 13): serves the viewer page for a finished run's directory or a saved map, with
// the run's trajectory, its map and how it ended, until SIGINT; a target that is neither is a clear error.
#include "crowdslam/io/trajectory.h"  // before httplib.h: its <resolv.h> defines `_res`, a name in Eigen
#include <gtest/gtest.h>
#include <httplib.h>

#include <nlohmann/json.hpp>

#include <csignal>
#include <fstream>
#include <map>
#include <regex>
#include <string>

#include "test_support.h"

using namespace crowdslam;
using namespace crowdslam::test;

namespace {
// The retained events a new client gets first, by name (data parsed).
std::map<std::string, nlohmann::json> first_events(int port) {
  std::map<std::string, nlohmann::json> events;
  std::string buffer;
  bool quiet = false;
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(10, 0);
  client.Get("/events", [&](const char* data, size_t size) {
    buffer.append(data, size);
    size_t end;
    while ((end = buffer.find("\n\n")) != std::string::npos) {
      const std::string message = buffer.substr(0, end);
      buffer.erase(0, end + 2);
      if (message.rfind(": keepalive", 0) == 0) quiet = true;
      std::smatch m;
      if (std::regex_search(message, m, std::regex("event: ([a-z_]+)\ndata: (.*)"))) {
        events[m[1]] = nlohmann::json::parse(m[2].str(), nullptr, false);
      }
    }
    // The retained messages come at once; the first keepalive (half a second without news) ends them.
    return !quiet;
  });
  return events;
}
}  // namespace

TEST(ViewCommand, ServesAFinishedRunAndItsSavedMapUntilInterrupted) {
  TempDir dir;
  const auto seq = dir / "seq";
  ASSERT_EQ(run_cli({"-q", "synth", "--out", seq.string(), "--frames", "60", "--width", "320", "--height", "240",
                     "--trajectory", "line"}).exit_code,
            0);
  const auto out = dir / "out";
  const auto map = dir / "map.db";
  ASSERT_EQ(run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter", "--save-map",
                     map.string()})
                .exit_code,
            0);
  const auto poses = io::read_trajectory((out / "CameraTrajectory.txt").string());
  ASSERT_GT(poses.size(), 10u);
  std::ifstream run_json(out / "run.json");
  const auto summary = nlohmann::json::parse(run_json)["summary"];

  for (const auto& target : {out, map}) {
    CliProcess view({"view", target.string(), "--viewer-port", "0"});
    const int port = wait_for_viewer_port(view);
    ASSERT_GT(port, 0) << view.current_stderr();
    const auto events = first_events(port);
    ASSERT_TRUE(events.count("map")) << target;
    // The saved map, as the run's summary counts it.
    EXPECT_EQ(events.at("map")["keyframes"].size(), summary["keyframes"].get<size_t>()) << target;
    EXPECT_EQ(events.at("map")["point_ids"].size(), summary["map_points"].get<size_t>()) << target;
    EXPECT_GT(summary["map_points"].get<size_t>(), 100u);
    ASSERT_TRUE(events.count("trajectory")) << target;
    if (target == out) {
      // Every pose of the run, and how it ended.
      EXPECT_EQ(events.at("trajectory")["positions"].size(), 3 * poses.size());
      ASSERT_TRUE(events.count("finish"));
      EXPECT_EQ(events.at("finish")["end_state"], "completed");
    }
    view.send_signal(SIGINT);
    EXPECT_EQ(view.wait(30).exit_code, 0) << view.current_stderr();
  }
}

TEST(ViewCommand, ATargetThatIsNeitherARunNorAMapIsAClearError) {
  TempDir dir;
  const auto empty = dir / "empty";
  std::filesystem::create_directories(empty);
  auto r = run_cli({"view", empty.string(), "--viewer-port", "0"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("no CameraTrajectory.txt"), std::string::npos) << r.err;
  r = run_cli({"view", (dir / "missing").string(), "--viewer-port", "0"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("neither a map file nor a run directory"), std::string::npos) << r.err;
}
