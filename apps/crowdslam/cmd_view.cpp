// `crowdslam view FILE.db | OUT/`: the live viewer's page for a saved map or a finished run's outputs,
// served until Ctrl-C.
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include "commands.h"
#include "crowdslam/io/dataset.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/mapdb/map_export.h"
#include "crowdslam/run/viewer_session.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/interrupt.h"
#include "crowdslam/viewer/event_stream.h"
#include "crowdslam/viewer/messages.h"
#include "crowdslam/viewer/viewer_server.h"

namespace crowdslam::app {

namespace {
namespace fs = std::filesystem;

system::MapSnapshot snapshot_of(const mapdb::MapContents& contents) {
  system::MapSnapshot s;
  for (const auto& p : contents.points) {
    s.points.push_back({p.id, static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z), p.observations});
  }
  for (const auto& kf : contents.keyframes) s.keyframes.push_back({kf.id, kf.timestamp_s, kf.world_from_cam});
  s.covisibility = contents.covisibility;
  s.loop_edges = contents.loop_edges;
  s.loops_closed = static_cast<int>(contents.loop_edges.size());
  return s;
}

system::MapSnapshot snapshot_of(const io::Trajectory& keyframes) {
  system::MapSnapshot s;
  uint64_t id = 0;
  for (const auto& pose : keyframes) s.keyframes.push_back({id++, pose.timestamp_s, pose.world_from_cam});
  return s;
}

// Publishes a saved map or a run directory's results into `stream` (retained for every client).
std::string publish_result(const fs::path& target, viewer::EventStream& stream) {
  if (fs::is_regular_file(target)) {
    const auto contents = mapdb::read_map_contents(target);
    stream.publish("map", viewer::map_json(snapshot_of(contents)));
    io::Trajectory keyframes;
    for (const auto& kf : contents.keyframes) keyframes.push_back({kf.timestamp_s, kf.world_from_cam});
    stream.publish("trajectory", viewer::trajectory_json(keyframes));
    return "map " + target.string() + ": " + std::to_string(contents.keyframes.size()) + " keyframes, " +
           std::to_string(contents.points.size()) + " points";
  }
  if (!fs::is_directory(target)) throw InputError(target.string() + ": neither a map file nor a run directory");
  const auto camera = target / "CameraTrajectory.txt";
  if (!fs::exists(camera)) throw InputError(target.string() + ": no CameraTrajectory.txt (not a run's --out directory)");
  const auto trajectory = io::read_trajectory(camera.string());
  // The run's saved map, if it has one; otherwise its keyframes.
  nlohmann::json run;
  if (std::ifstream in(target / "run.json"); in) {
    try {
      run = nlohmann::json::parse(in);
    } catch (const std::exception&) {
      spdlog::warn("{}: unreadable, showing the trajectories only", (target / "run.json").string());
    }
  }
  const auto saved = run.is_object() && run.contains("map") && run["map"].is_object() ? run["map"]["saved"] : nullptr;
  std::string what;
  if (saved.is_object() && saved.contains("path") && saved["path"].is_string() &&
      fs::is_regular_file(saved["path"].get<std::string>())) {
    const auto contents = mapdb::read_map_contents(saved["path"].get<std::string>());
    stream.publish("map", viewer::map_json(snapshot_of(contents)));
    what = ", map " + saved["path"].get<std::string>();
  } else if (fs::exists(target / "KeyFrameTrajectory.txt")) {
    stream.publish("map", viewer::map_json(snapshot_of(io::read_trajectory((target / "KeyFrameTrajectory.txt").string()))));
  }
  stream.publish("trajectory", viewer::trajectory_json(trajectory));
  // Ground truth of the run's dataset, aligned as the ATE is.
  if (run.is_object() && run.contains("dataset") && run["dataset"].is_string()) {
    try {
      const auto source = io::open_source(run["dataset"].get<std::string>());
      const auto ground_truth = source->ground_truth();
      std::vector<std::pair<double, geometry::Vec3>> estimate;
      for (const auto& pose : trajectory) estimate.emplace_back(pose.timestamp_s, pose.world_from_cam.translation());
      const bool mono = run.contains("sensor") && run["sensor"] == "mono";
      if (const auto alignment = viewer::align_ground_truth(ground_truth, estimate, mono)) {
        stream.publish("ground_truth", viewer::ground_truth_json(ground_truth, *alignment, 3000));
      }
    } catch (const std::exception& e) {
      spdlog::info("no ground truth shown: {}", e.what());
    }
  }
  const bool has_end = run.is_object() && run.contains("end_state") && run["end_state"].is_string();
  stream.publish("finish", nlohmann::json({{"end_state", has_end ? run["end_state"].get<std::string>() : "?"}}).dump());
  return "run " + target.string() + ": " + std::to_string(trajectory.size()) + " poses" + what;
}
}  // namespace

void add_view_command(CLI::App& app, const GlobalOptions& global) {
  struct ViewArgs {
    std::string target;
    viewer::ViewerServerOptions server;
  };
  auto args = std::make_shared<ViewArgs>();
  auto* cmd = app.add_subcommand("view", "Serve the viewer page for a saved map (FILE.db) or a finished run (OUT/)");
  cmd->add_option("target", args->target, "A map saved with --save-map, or a run's --out directory")->required();
  cmd->add_option("--viewer-host", args->server.host, "Address to listen on (default 127.0.0.1; no authentication)");
  cmd->add_option("--viewer-port", args->server.port, "Port (default 8080; 0: any free port)")->check(CLI::Range(0, 65535));
  cmd->callback([args, &global] {
    viewer::EventStream stream;
    const std::string what = publish_result(args->target, stream);
    viewer::ViewerServer server(args->server, stream, nullptr, [] { return std::string("{\"finished\":true}"); });
    InterruptScope interrupts;
    server.start();
    // The URL is the result: on stderr whatever the log level (with port 0 the only way to learn the
    // port), and on stdout (with --json as its one document).
    std::cerr << "viewer: " << server.url() << " (" << what << "); Ctrl-C to stop" << std::endl;
    if (!run::is_loopback_host(args->server.host)) {
      spdlog::warn("viewer: listening on {}, not a loopback address: anyone who can reach it can see this map "
                   "(no authentication)",
                   args->server.host);
    }
    if (global.json) {
      print_json({{"url", server.url()}, {"port", server.port()}, {"target", args->target}, {"showing", what}});
    } else {
      std::cout << server.url() << std::endl;
    }
    while (!interrupted()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    clear_interrupt();
    server.stop();
  });
}

}  // namespace crowdslam::app
