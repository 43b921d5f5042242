#include "crowdslam/run/map_files.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <ctime>
#include <filesystem>

#include "crowdslam/mapdb/map_target.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"
#include "crowdslam/util/version.h"

namespace crowdslam::run {

namespace {
double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void check_map_options(const RunOptions& options) {
  if (options.localization && options.load_map.empty()) {
    throw InputError("--localization needs --load-map FILE.db (the map to localise in)");
  }
  if (options.localization && !options.save_map.empty()) {
    throw InputError("--save-map with --localization: a localisation run does not change the map, nothing to save");
  }
  // Only a new file, or (with --overwrite) a crowdslam map, is replaced: never a device, a FIFO, a
  // settings file or a dataset's list (mapdb/map_target.h).
  if (options.save_map_given || !options.save_map.empty()) {
    mapdb::check_map_target(options.save_map, options.overwrite, "--save-map");
    // Nor one of the run's own outputs, written after the map.
    std::error_code ec;
    const auto map_path = std::filesystem::weakly_canonical(options.save_map, ec);
    const auto out = std::filesystem::weakly_canonical(options.out_dir, ec);
    for (const char* name : {"run.json", "CameraTrajectory.txt", "KeyFrameTrajectory.txt", "BridgedTrajectory.txt",
                             "report.html", "frames"}) {
      if (!ec && map_path == out / name) {
        throw InputError("--save-map " + clip_text(options.save_map) + ": is one of the run's outputs in --out");
      }
    }
  }
}

nlohmann::json load_map_if_requested(const RunOptions& options, system::System& slam) {
  if (options.load_map.empty() && options.save_map.empty()) return nullptr;
  nlohmann::json map_json = nlohmann::json::object();
  map_json["loaded"] = nullptr;
  map_json["saved"] = nullptr;
  if (options.load_map.empty()) return map_json;
  const auto start = std::chrono::steady_clock::now();
  const auto loaded = slam.load_map(options.load_map, options.localization);
  map_json["loaded"] = {{"path", options.load_map},
                        {"mode", options.localization ? "localization" : "continue_mapping"},
                        {"keyframes", loaded.keyframes.size()},
                        {"map_points", loaded.map_points},
                        {"load_ms", ms_since(start)},
                        {"origin",
                         {{"dataset", loaded.header.origin.dataset},
                          {"created_utc", loaded.header.origin.created_utc},
                          {"crowdslam_version", loaded.header.origin.crowdslam_version},
                          {"end_state", loaded.header.origin.end_state}}}};
  return map_json;
}

void add_localization_stats(const std::vector<system::FrameReport>& reports, nlohmann::json& map_json) {
  if (map_json.is_null() || map_json["loaded"].is_null()) return;
  size_t localised = 0;
  size_t relocalisations = 0;
  std::optional<size_t> first;
  bool was_ok = false;
  for (const auto& r : reports) {
    const bool ok = r.state == tracking::TrackingState::kOk;
    if (ok) {
      ++localised;
      if (!first) first = r.index;
      if (r.method == "relocalization" && !was_ok) ++relocalisations;
    }
    was_ok = ok;
  }
  auto& loaded = map_json["loaded"];
  loaded["frames"] = reports.size();
  loaded["frames_localized"] = localised;
  loaded["frames_not_localized"] = reports.size() - localised;
  loaded["relocalizations"] = relocalisations;
  if (first) {
    loaded["first_localized_frame"] = *first;
    loaded["time_to_first_localization_s"] = reports[*first].timestamp_s - reports.front().timestamp_s;
  } else {
    loaded["first_localized_frame"] = nullptr;
    loaded["time_to_first_localization_s"] = nullptr;
    spdlog::warn("{}: the run never localised in the loaded map ({} frames)", clip_text(map_json["loaded"]["path"].get<std::string>()),
                 reports.size());
  }
}

void save_map_if_requested(const RunOptions& options, const system::System& slam, const std::string& end_state,
                           nlohmann::json& map_json) {
  if (options.save_map.empty()) return;
  mapdb::MapOrigin origin;
  origin.dataset = options.dataset;
  origin.created_utc = utc_now();
  origin.crowdslam_version = crowdslam::version();
  origin.end_state = end_state;
  const auto start = std::chrono::steady_clock::now();
  slam.save_map(options.save_map, origin);
  const double ms = ms_since(start);
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(options.save_map, ec);
  map_json["saved"] = {{"path", options.save_map},
                       {"keyframes", slam.num_keyframes()},
                       {"map_points", slam.num_map_points()},
                       {"bytes", ec ? 0 : bytes},
                       {"save_ms", ms}};
  spdlog::info("map saved to {}: {} keyframes, {} points, {:.1f} MB in {:.0f} ms", clip_text(options.save_map),
               slam.num_keyframes(), slam.num_map_points(), static_cast<double>(bytes) / 1e6, ms);
}

}  // namespace crowdslam::run
