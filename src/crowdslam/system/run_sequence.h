#pragma once
// `crowdslam run`: runs the system over a whole sequence and writes the outputs:
//   OUT/CameraTrajectory.txt    every tracked frame (TUM format unless Output.trajectory_format says otherwise)
//   OUT/KeyFrameTrajectory.txt  the keyframes left in the map
//   OUT/run.json                settings used, per-frame timings and states, summary, accuracy when ground
//                               truth is available
//   OUT/frames/NNNNNN.jpg       with --save-frames N: every N-th frame with person boxes (blue), kept
//                               keypoints (green) and keypoints removed by the people filter (red)
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
  bool people_filter = true;        // --no-people-filter: static-world baseline (no filter, no FNU)
  std::string detections_file;      // --detections: MOT-format boxes instead of the network
  std::string detector_model;       // --detector: body | coco | PATH.cfg | PATH.onnx
  std::string filter_mode;          // --filter-mode: overrides PeopleFilter.mode (paper | depth)
  size_t save_frames = 0;           // --save-frames N: every N-th frame drawn into OUT/frames/
  std::string vocabulary;           // --vocabulary FILE | none ("" = the default vocabulary)
  bool loop_closing = true;         // --no-loop-closing
};

struct RunSummary {
  size_t frames = 0;
  size_t tracked = 0;
  double tracked_percent = 0;
  std::optional<size_t> init_frame;  // index of the first frame that initialised a map
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
