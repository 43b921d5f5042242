#pragma once
// `crowdslam run`: runs the system over a whole sequence and writes the outputs:
//   OUT/CameraTrajectory.txt    every tracked frame (TUM format unless Output.trajectory_format says otherwise)
//   OUT/KeyFrameTrajectory.txt  the keyframes left in the map
//   OUT/run.json                settings used, per-frame timings and states, summary, accuracy when ground
//                               truth is available
// Files are written only when the run completes (each atomically); a failed run leaves nothing behind.
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "crowdslam/io/dataset.h"

namespace crowdslam::system {

struct RunOptions {
  std::string dataset;        // directory, video file or camera index
  std::string settings_path;  // empty: DATASET/settings.yaml
  std::string out_dir;
  std::optional<io::SensorKind> sensor;  // override the sensor detected from the dataset
  bool sequential = false;
  size_t max_frames = 0;  // 0 = all
  bool progress = true;
};

struct RunSummary {
  size_t frames = 0;
  size_t tracked = 0;
  double tracked_percent = 0;
  double throughput_fps = 0;
  double tracking_ms_median = 0;
  double tracking_ms_p95 = 0;
  double extraction_ms_median = 0;
  double total_ms_median = 0;
  double total_ms_p95 = 0;
  std::optional<double> ate_rmse_m;
  std::optional<double> rpe_trans_rmse_m;
  nlohmann::json json;  // the whole run.json document
};

RunSummary run_sequence(const RunOptions& options);

}  // namespace crowdslam::system
