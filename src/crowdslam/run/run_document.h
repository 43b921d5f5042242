#pragma once
// run.json: the document a run writes, assembled from the frames' reports and the system's statistics,
// and the accuracy of each map segment against the ground truth.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "crowdslam/io/settings.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/run/run_sequence.h"
#include "crowdslam/system/system.h"

namespace crowdslam::run {

nlohmann::json frame_json(const system::FrameReport& report);
nlohmann::json segment_json(const system::MapSegment& segment);

// ATE (Sim3 for monocular, else SE3) and RPE of every segment with at least 3 poses, and the figures of
// the longest segment (most poses) in the summary. `ground_truth_name` names the file in messages.
// `keyframes` (KeyFrameTrajectory.txt): each segment's keyframes (those in its time span) get their own
// ATE, `ate_keyframes_rmse_m`, the figure ORB-SLAM2's evaluations report. `bridged`: each segment's
// bridged frames, whose drift is reported as `bridged` (bridge_accuracy.h).
void evaluate_accuracy(const io::Trajectory& ground_truth, const std::string& ground_truth_name,
                       const std::vector<io::Trajectory>& segments, const std::vector<io::Trajectory>& bridged,
                       const std::vector<system::MapSegment>& info, const io::Trajectory& keyframes,
                       bool monocular, RunSummary& summary, nlohmann::json& accuracy);

// Timing statistics over the frames (median, p95) into `summary`.
void summarise_frames(const std::vector<system::FrameReport>& reports, RunSummary& summary);

double percentile(std::vector<double> values, double q);
// The value, or null.
nlohmann::json optional_json(const std::optional<double>& value);
// The dataset as run.json names it: an existing path made absolute (the report finds the ground truth
// from any working directory), anything else (a camera index) as given.
std::string dataset_path(const std::string& spec);

// The run.json header written before the first frame ("end_state": "running").
nlohmann::json running_document(const RunOptions& options, const std::string& settings_path, io::SensorKind sensor);

// The complete document at the end.
struct RunContext {
  const RunOptions& options;
  const std::string& settings_path;
  io::SensorKind sensor;
  const io::Settings& run_settings;
  const system::System& slam;
  double wall_s;
  const std::vector<double>& load_ms;
  nlohmann::json input;  // input warnings and skipped frames
  nlohmann::json map;    // loaded / saved map (run/map_files.h), null without either
  nlohmann::json filter_score = nullptr;  // --score-filter (filter_mask_score.h): run.json people_masks
};
nlohmann::json final_document(const RunContext& context, const std::vector<system::FrameReport>& reports,
                              const RunSummary& summary, const nlohmann::json& accuracy);

}  // namespace crowdslam::run
