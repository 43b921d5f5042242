#include "crowdslam/run/run_document.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <unordered_set>

#include "crowdslam/eval/ate.h"
#include "crowdslam/eval/rpe.h"
#include "crowdslam/run/bridge_accuracy.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"
#include "crowdslam/util/version.h"

namespace crowdslam::run {

nlohmann::json optional_json(const std::optional<double>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

std::string dataset_path(const std::string& spec) {
  std::error_code ec;
  if (spec.empty() || !std::filesystem::exists(spec, ec)) return spec;  // a camera index
  // Not lexically normalised: "a/link/.." is not "a" when link is a symbolic link.
  const auto absolute = std::filesystem::absolute(spec, ec);
  return ec ? spec : absolute.string();
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const auto lower = static_cast<size_t>(std::floor(position));
  const auto upper = std::min(values.size() - 1, lower + 1);
  const double t = position - static_cast<double>(lower);
  return values[lower] * (1 - t) + values[upper] * t;
}

nlohmann::json frame_json(const system::FrameReport& r) {
  return {{"index", r.index},
          {"person_boxes", r.person_boxes},
          {"people_area", r.people_area},
          {"keypoints_before_filter", r.keypoints_before_filter},
          {"detector_ms", r.detector_ms},
          {"detector_wait_ms", r.detector_wait_ms},
          {"detection_frame", r.detection_frame},
          {"boxes_propagated", r.boxes_propagated},
          {"rescued_with_boxes", r.rescued_with_boxes},
          {"box_matches", r.box_matches},
          {"static_boxes", r.static_boxes},
          {"keypoints_dynamic", r.keypoints_dynamic},
          {"dynamic_grown", r.dynamic_grown},
          {"matches_moving", r.matches_moving},
          {"points_culled_moving", r.points_culled_moving},
          {"points_seen_through", r.points_seen_through},
          {"dynamic_check_skipped", r.dynamic_check_skipped},
          {"stereo_matches", r.stereo_matches},
          {"right_keypoints_removed", r.right_keypoints_removed},
          {"flat_boxes", r.flat_boxes},
          {"right_wait_ms", r.right_wait_ms},
          {"stereo_match_ms", r.stereo_match_ms},
          {"timestamp", r.timestamp_s},
          {"extraction_ms", r.extraction_ms},
          {"tracking_ms", r.tracking_ms},
          {"total_ms", r.extraction_ms + r.detector_wait_ms + r.tracking_ms},
          {"keypoints", r.keypoints},
          {"feature_budget", r.feature_budget},
          {"tracked_points", r.tracked_points},
          {"state", tracking::to_string(r.state)},
          {"method", r.method},
          {"keyframe", r.new_keyframe},
          {"waited_for_mapping_ms", r.waited_for_mapping_ms},
          {"localized_after_init", false},
          {"localized_after_reanchor", false}};
}

nlohmann::json segment_json(const system::MapSegment& s) {
  return {{"map_id", s.map_id},
          {"first_frame", s.first_frame},
          {"last_frame", s.last_frame},
          {"frames", s.frames},
          {"tracked", s.tracked},
          {"first_stamp", s.tracked > 0 ? nlohmann::json(s.first_stamp_s) : nlohmann::json(nullptr)},
          {"last_stamp", s.tracked > 0 ? nlohmann::json(s.last_stamp_s) : nlohmann::json(nullptr)},
          {"keyframes", s.keyframes}};
}

// Null when the ground is not held (not monocular, or Ground.enabled 0).
nlohmann::json ground_json(const system::System& slam) {
  if (!slam.ground()) return nullptr;
  nlohmann::json doc = {{"keyframe_sigma", slam.ground()->keyframe_sigma}, {"final_global_ba", nullptr}};
  if (const auto& f = slam.final_ground_ba()) {
    doc["final_global_ba"] = {{"applied", f->applied},
                              {"keyframes", f->keyframes},
                              {"keyframes_with_ground", f->stats.ground_keyframes},
                              {"ground_points", f->stats.ground_points},
                              {"ground_height", f->stats.ground_height},
                              {"initial_cost", f->stats.last_initial_cost},
                              {"final_cost", f->stats.last_final_cost},
                              {"iterations", f->stats.last_iterations},
                              {"time_ms", f->stats.time_ms_total}};
  }
  return doc;
}

void summarise_frames(const std::vector<system::FrameReport>& reports, RunSummary& summary) {
  std::vector<double> tracking_ms, extraction_ms, total_ms;
  // Bridged frames a monocular re-anchoring localised afterwards are tracked, not bridged.
  std::unordered_set<size_t> localized_later;
  for (const auto& r : reports) {
    localized_later.insert(r.localized_after_reanchor.begin(), r.localized_after_reanchor.end());
  }
  for (const auto& r : reports) {
    if (!summary.init_frame && r.method == std::string("init")) summary.init_frame = r.index;
    summary.frames_localized_before_init += r.localized_before_init.size();
    summary.frames_localized_after_reanchor += r.localized_after_reanchor.size();
    if (r.state == tracking::TrackingState::kBridged && !localized_later.count(r.index)) ++summary.bridged;
    tracking_ms.push_back(r.tracking_ms);
    extraction_ms.push_back(r.extraction_ms);
    total_ms.push_back(r.extraction_ms + r.detector_wait_ms + r.tracking_ms);
  }
  summary.tracking_ms_median = percentile(tracking_ms, 0.5);
  summary.tracking_ms_p95 = percentile(tracking_ms, 0.95);
  summary.extraction_ms_median = percentile(extraction_ms, 0.5);
  summary.total_ms_median = percentile(total_ms, 0.5);
  summary.total_ms_p95 = percentile(total_ms, 0.95);
}

namespace {
// The ATE of the keyframes in the time span of one segment's camera trajectory (own alignment).
nlohmann::json keyframe_ate(const io::Trajectory& ground_truth, const std::string& ground_truth_name,
                            const io::Trajectory& segment, const io::Trajectory& keyframes,
                            const eval::AteOptions& options, int map_id) {
  double first = segment.front().timestamp_s;
  double last = first;
  for (const auto& pose : segment) {
    first = std::min(first, pose.timestamp_s);
    last = std::max(last, pose.timestamp_s);
  }
  io::Trajectory in_span;
  for (const auto& pose : keyframes) {
    if (pose.timestamp_s >= first && pose.timestamp_s <= last) in_span.push_back(pose);
  }
  nlohmann::json out = {{"ate_keyframes_poses", in_span.size()}};
  if (in_span.size() < 3) return out;
  try {
    const auto ate = eval::evaluate_ate(ground_truth, in_span, options, ground_truth_name,
                                        "KeyFrameTrajectory.txt (map " + std::to_string(map_id) + ")");
    out["ate_keyframes_rmse_m"] = ate.translation_error_m.rmse;
  } catch (const InputError& e) {
    out["ate_keyframes_error"] = e.what();
  }
  return out;
}
}  // namespace

void evaluate_accuracy(const io::Trajectory& ground_truth, const std::string& ground_truth_name,
                       const std::vector<io::Trajectory>& segments, const std::vector<io::Trajectory>& bridged,
                       const std::vector<system::MapSegment>& info, const io::Trajectory& keyframes,
                       bool monocular, RunSummary& summary, nlohmann::json& accuracy) {
  accuracy = nullptr;
  if (ground_truth.empty()) return;
  nlohmann::json per_segment = nlohmann::json::array();
  std::optional<size_t> longest;
  for (size_t k = 0; k < segments.size(); ++k) {
    if (segments[k].empty()) continue;
    if (!longest || segments[k].size() > segments[*longest].size()) longest = k;
  }
  nlohmann::json longest_json = nullptr;
  for (size_t k = 0; k < segments.size(); ++k) {
    const io::Trajectory& trajectory = segments[k];
    if (trajectory.empty()) continue;
    SegmentAccuracy result;
    result.map_id = k < info.size() ? info[k].map_id : static_cast<int>(k);
    result.poses = trajectory.size();
    nlohmann::json entry = {{"map_id", result.map_id}, {"poses", result.poses}};
    const std::string name = "CameraTrajectory.txt (map " + std::to_string(result.map_id) + ")";
    if (trajectory.size() < 3) {
      result.error = "fewer than 3 poses";
    } else {
      try {
        eval::AteOptions ate_options;
        ate_options.alignment = monocular ? eval::Alignment::kSim3 : eval::Alignment::kSe3;
        const auto ate = eval::evaluate_ate(ground_truth, trajectory, ate_options, ground_truth_name, name);
        result.ate_rmse_m = ate.translation_error_m.rmse;
        entry.update({{"ate_rmse_m", ate.translation_error_m.rmse},
                      {"ate_mean_m", ate.translation_error_m.mean},
                      {"ate_median_m", ate.translation_error_m.median},
                      {"ate_max_m", ate.translation_error_m.max},
                      {"ate_pairs", ate.matches.size()},
                      {"alignment", eval::to_string(ate_options.alignment)}});
        if (monocular) entry["sim3_scale"] = ate.alignment.scale;
        if (k < bridged.size() && !bridged[k].empty())
          entry["bridged"] = bridge_accuracy(ground_truth, trajectory, bridged[k], ate, ate_options.max_difference_s);
        entry.update(
            keyframe_ate(ground_truth, ground_truth_name, trajectory, keyframes, ate_options, result.map_id));
        // Monocular trajectories have an arbitrary scale: RPE at the aligned scale.
        eval::RpeOptions rpe_options;
        if (monocular) rpe_options.scale = ate.alignment.scale;
        try {
          const auto rpe = eval::evaluate_rpe(ground_truth, trajectory, rpe_options, ground_truth_name, name);
          result.rpe_trans_rmse_m = rpe.translation_error_m.rmse;
          entry["rpe_trans_rmse_m_per_s"] = rpe.translation_error_m.rmse;
          entry["rpe_rot_rmse_deg_per_s"] = rpe.rotation_error_deg.rmse;
        } catch (const InputError& e) {
          entry["rpe_error"] = e.what();
          if (longest && k == *longest) spdlog::warn("RPE not evaluated (the ATE is): {}", e.what());
        }
      } catch (const InputError& e) {
        result.error = e.what();
      }
    }
    if (!result.error.empty()) {
      entry["error"] = result.error;
      if (longest && k == *longest)
        spdlog::warn("accuracy of map {} not evaluated: {}", result.map_id, result.error);
    }
    if (longest && k == *longest) {
      summary.ate_rmse_m = result.ate_rmse_m;
      summary.rpe_trans_rmse_m = result.rpe_trans_rmse_m;
      if (result.ate_rmse_m) summary.evaluated_map_id = result.map_id;
      longest_json = entry;
    }
    summary.segment_accuracy.push_back(result);
    per_segment.push_back(entry);
  }
  if (longest_json.is_null()) return;
  accuracy = longest_json;
  accuracy["evaluated"] = segments.size() > 1 ? "longest map segment" : "whole trajectory";
  accuracy["segments"] = per_segment;
}

nlohmann::json running_document(const RunOptions& options, const std::string& settings_path,
                                io::SensorKind sensor) {
  return {
      {"crowdslam_version", crowdslam::version()}, {"git_commit", crowdslam::git_commit()},
      {"end_state", "running"},
      {"pid", static_cast<long>(::getpid())},     {"started", utc_now()},
      {"dataset", dataset_path(options.dataset)}, {"settings", settings_path},
      {"sensor", io::to_string(sensor)},          {"mode", options.sequential ? "sequential" : "threaded"}};
}

nlohmann::json final_document(const RunContext& c, const std::vector<system::FrameReport>& reports,
                              const RunSummary& summary, const nlohmann::json& accuracy) {
  const auto& slam = c.slam;
  const auto& s = c.run_settings;
  nlohmann::json doc = running_document(c.options, c.settings_path, c.sensor);
  doc.erase("pid");
  doc["end_state"] = summary.end.to_string();
  doc["finished"] = utc_now();
  doc["background_nice"] = c.options.background_nice;  // threaded mode: mapping and loop closing
  if (const auto& vocabulary = slam.vocabulary_info()) {
    doc["vocabulary"] = {
        {"path", vocabulary->path}, {"words", vocabulary->words}, {"load_ms", vocabulary->load_ms}};
  } else {
    doc["vocabulary"] = nullptr;
  }
  std::vector<double> detector_ms, detector_wait_ms;
  int rescued = 0, frames_with_box_matches = 0, frames_with_static_boxes = 0;
  long box_matches = 0;
  double waited_for_mapping_ms = 0;
  int frames_waited = 0;
  long dynamic_total = 0, grown_total = 0, culled_total = 0, seen_through_total = 0;
  int frames_with_dynamic = 0;
  int frames_check_skipped = 0;
  for (const auto& r : reports) {
    dynamic_total += r.keypoints_dynamic;
    grown_total += r.dynamic_grown;
    culled_total += r.points_culled_moving;
    seen_through_total += r.points_seen_through;
    frames_with_dynamic += r.keypoints_dynamic > 0 ? 1 : 0;
    frames_check_skipped += r.dynamic_check_skipped ? 1 : 0;
    rescued += r.rescued_with_boxes ? 1 : 0;
    frames_with_box_matches += r.box_matches > 0 ? 1 : 0;
    box_matches += r.box_matches;
    frames_with_static_boxes += r.static_boxes > 0 ? 1 : 0;
    if (r.detector_ms > 0) detector_ms.push_back(r.detector_ms);  // latest mode: frames with a new detection
    detector_wait_ms.push_back(r.detector_wait_ms);
    waited_for_mapping_ms += r.waited_for_mapping_ms;
    frames_waited += r.waited_for_mapping_ms > 0 ? 1 : 0;
  }
  const people::PeopleStage* people = slam.people_stage();
  doc["people_filter"] =
      people != nullptr ? nlohmann::json{{"detector", slam.detector_name()},
                                         {"detector_mode", people::to_string(people->mode())},
                                         {"latest_interval", s.detector.latest_interval},
                                         {"box_tracker", people->tracker_enabled()},
                                         {"detections", people->stats().detections},
                                         {"frames_detected", people->stats().frames_detected},
                                         {"frames_propagated", people->stats().frames_propagated},
                                         {"boxes_moved", people->stats().boxes_moved},
                                         {"boxes_kept_in_place", people->stats().boxes_kept_in_place},
                                         {"tracks_started", people->stats().tracks_started},
                                         {"flat_boxes", people->stats().flat_boxes},
                                         {"frames_with_flat_boxes", people->stats().frames_with_flat_boxes},
                                         {"flat_box_margin_m", s.people_filter.flat_box_margin_m},
                                         {"mode", s.people_filter.mode},
                                         {"margin_px", s.people_filter.margin_px},
                                         {"segment_from_m", s.people_filter.segment_from_m},
                                         {"filter_before_nms", people->filter_before_nms()},
                                         {"raw_box_max_area_ratio", s.detector.raw_box_max_area_ratio},
                                         {"raw_boxes_dropped", people->stats().raw_boxes_dropped},
                                         {"static_in_boxes", s.people_filter.static_in_boxes},
                                         {"static_check_below", s.people_filter.static_check_below},
                                         {"frames_with_box_matches", frames_with_box_matches},
                                         {"box_matches", box_matches},
                                         {"frames_with_static_boxes", frames_with_static_boxes},
                                         {"frames_rescued_with_boxes", rescued},
                                         {"feature_budget", s.feature_budget.enabled},
                                         {"area", s.feature_budget.area},
                                         {"detector_ms_median", percentile(detector_ms, 0.5)},
                                         {"detector_wait_ms_median", percentile(detector_wait_ms, 0.5)},
                                         {"detector_wait_ms_p95", percentile(detector_wait_ms, 0.95)}}
                        : nlohmann::json(nullptr);
  if (!c.filter_score.is_null()) doc["people_masks"] = c.filter_score;  // also without the filter
  doc["ground"] = ground_json(slam);
  const auto& g = s.geometry;
  doc["geometry"] = {{"dynamic_check", g.dynamic_check},
                     {"moving_factor", g.moving_factor},
                     {"cull_score", g.cull_score},
                     {"region_radius_px", g.region_radius_px},
                     {"free_space_margin_m", g.free_space_margin_m},
                     {"free_space_cull_run", g.free_space_cull_run},
                     {"keypoints_dynamic", dynamic_total},
                     {"keypoints_grown", grown_total},
                     {"frames_with_dynamic", frames_with_dynamic},
                     {"map_points_culled_moving", culled_total},
                     {"map_point_verdicts_seen_through", seen_through_total},
                     {"frames_tracked_without_check", frames_check_skipped}};
  doc["summary"] = {
      {"frames", summary.frames},
      {"tracked_frames", summary.tracked},
      {"tracked_percent", summary.tracked_percent},
      {"bridged_frames", summary.bridged},
      {"init_frame", summary.init_frame ? nlohmann::json(*summary.init_frame) : nlohmann::json(nullptr)},
      {"frames_localized_before_init", summary.frames_localized_before_init},
      {"frames_localized_after_reanchor", summary.frames_localized_after_reanchor},
      {"wall_time_s", c.wall_s},
      {"throughput_fps", summary.throughput_fps},
      {"tracking_ms_median", summary.tracking_ms_median},
      {"tracking_ms_p95", summary.tracking_ms_p95},
      {"extraction_ms_median", summary.extraction_ms_median},
      {"total_ms_median", summary.total_ms_median},
      {"total_ms_p95", summary.total_ms_p95},
      {"load_wait_ms_median", percentile(c.load_ms, 0.5)},
      {"keyframes", slam.num_keyframes()},
      {"map_points", slam.num_map_points()},
      {"map_resets", slam.map_resets()},
      {"reanchors", slam.reanchors()},
      {"waited_for_mapping_ms", waited_for_mapping_ms},
      {"frames_waited_for_mapping", frames_waited},
      {"ate_rmse_m", optional_json(summary.ate_rmse_m)},
      {"ate_map_id",
       summary.evaluated_map_id ? nlohmann::json(*summary.evaluated_map_id) : nlohmann::json(nullptr)}};
  nlohmann::json segments = nlohmann::json::array();
  for (const auto& segment : summary.segments) segments.push_back(segment_json(segment));
  doc["segments"] = segments;
  doc["input"] = c.input;
  doc["map"] = c.map;
  const auto mapper = slam.mapper_stats();
  const int processed = std::max(1, mapper.keyframes_processed);
  doc["local_mapping"] = {{"keyframes_processed", mapper.keyframes_processed},
                          {"points_created", mapper.points_created},
                          {"points_culled", mapper.points_culled},
                          {"keyframes_culled", mapper.keyframes_culled},
                          {"ba_runs", mapper.ba_runs},
                          {"ba_aborted", mapper.ba_aborted},
                          {"ba_relative_poses", mapper.ba_relative_poses},
                          {"ba_ms_mean", mapper.ba_runs > 0 ? mapper.ba_time_ms_total / mapper.ba_runs : 0.0},
                          {"register_ms_mean", mapper.register_ms_total / processed},
                          {"triangulation_ms_mean", mapper.triangulation_ms_total / processed},
                          {"fusion_ms_mean", mapper.fusion_ms_total / processed},
                          {"culling_ms_mean", mapper.culling_ms_total / processed},
                          {"keyframe_ms_mean", mapper.processing_ms_total / processed}};
  // Per keyframe: median and p95 of each step and of the whole.
  const auto step = [&](double mapping::KeyframeStepTimes::*field) {
    std::vector<double> values;
    values.reserve(mapper.per_keyframe.size());
    for (const auto& k : mapper.per_keyframe) values.push_back(k.*field);
    return nlohmann::json{{"median", percentile(values, 0.5)}, {"p95", percentile(values, 0.95)}};
  };
  doc["local_mapping"]["per_keyframe_ms"] = {
      {"register", step(&mapping::KeyframeStepTimes::register_ms)},
      {"triangulation", step(&mapping::KeyframeStepTimes::triangulation_ms)},
      {"fusion", step(&mapping::KeyframeStepTimes::fusion_ms)},
      {"local_ba", step(&mapping::KeyframeStepTimes::ba_ms)},
      {"culling", step(&mapping::KeyframeStepTimes::culling_ms)},
      {"total", step(&mapping::KeyframeStepTimes::total_ms)}};
  // Each keyframe's times, in the order the mapper processed them (n counts from 0; the mapper does not
  // record keyframe ids with its times).
  nlohmann::json keyframe_times = nlohmann::json::array();
  for (size_t n = 0; n < mapper.per_keyframe.size(); ++n) {
    const auto& k = mapper.per_keyframe[n];
    keyframe_times.push_back({{"n", n},
                              {"register", k.register_ms},
                              {"triangulation", k.triangulation_ms},
                              {"fusion", k.fusion_ms},
                              {"local_ba", k.ba_ms},
                              {"culling", k.culling_ms},
                              {"total", k.total_ms}});
  }
  doc["local_mapping"]["keyframe_times_ms"] = std::move(keyframe_times);
  if (slam.loop_closing_enabled()) {
    const auto loops = slam.loop_stats();
    nlohmann::json events = nlohmann::json::array();
    for (const auto& e : loops.loops) {
      events.push_back({{"keyframe", e.keyframe_id},
                        {"loop_keyframe", e.loop_keyframe_id},
                        {"timestamp", e.timestamp_s},
                        {"loop_timestamp", e.loop_timestamp_s},
                        {"matches", e.matches},
                        {"correction_ms", e.correction_ms}});
    }
    doc["loop_closing"] = {
        {"keyframes_checked", loops.keyframes_checked},
        {"candidates_consistent", loops.candidates_consistent},
        {"candidates_rejected", loops.candidates_rejected},
        {"loops_confirmed_by_covisibles", loops.loops_confirmed_by_covisibles},
        {"loops", events},
        {"detection_ms_mean", loops.detection_ms_total / std::max(1, loops.keyframes_checked)},
        {"global_ba_runs", loops.global_ba.runs},
        {"global_ba_applied", loops.global_ba.applied},
        {"global_ba_aborted", loops.global_ba.aborted},
        {"global_ba_ms_mean", loops.global_ba.time_ms_total / std::max(1, loops.global_ba.runs)}};
  } else {
    doc["loop_closing"] = nullptr;
  }
  doc["accuracy"] = accuracy;
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& r : reports) frames.push_back(frame_json(r));
  // Frames the monocular initialisation or re-anchoring localised afterwards: tracked (they have a pose in
  // the trajectory) although their own report, made before, says not initialised or lost.
  for (const auto& r : reports) {
    for (const size_t index : r.localized_before_init) {
      if (index < frames.size()) frames[index]["localized_after_init"] = true;
    }
    for (const size_t index : r.localized_after_reanchor) {
      if (index < frames.size()) frames[index]["localized_after_reanchor"] = true;
    }
  }
  doc["frames"] = std::move(frames);
  return doc;
}

}  // namespace crowdslam::run
