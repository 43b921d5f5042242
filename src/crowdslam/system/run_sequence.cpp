#include "crowdslam/system/run_sequence.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/eval/ate.h"
#include "crowdslam/eval/rpe.h"
#include "crowdslam/io/euroc_dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/system/frame_prefetcher.h"
#include "crowdslam/system/system.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"

namespace crowdslam::system {

namespace {

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const auto lower = static_cast<size_t>(std::floor(position));
  const auto upper = std::min(values.size() - 1, lower + 1);
  const double t = position - static_cast<double>(lower);
  return values[lower] * (1 - t) + values[upper] * t;
}

io::TrajectoryFormat parse_format(const std::string& name) {
  if (name == "kitti") return io::TrajectoryFormat::kKitti;
  if (name == "euroc") return io::TrajectoryFormat::kEuroc;
  return io::TrajectoryFormat::kTum;
}

cv::Mat draw_frame(const cv::Mat& colour, const FrameReport& r) {
  cv::Mat canvas;
  if (colour.channels() == 1) {
    cv::cvtColor(colour, canvas, cv::COLOR_GRAY2BGR);
  } else {
    canvas = colour.clone();
  }
  for (const auto& b : r.boxes) cv::rectangle(canvas, b.box, cv::Scalar(255, 80, 0), 2);
  for (const auto& k : r.kept_keypoints) cv::circle(canvas, k.pt, 3, cv::Scalar(0, 200, 0), 1);
  for (const auto& k : r.removed_keypoints) cv::circle(canvas, k.pt, 3, cv::Scalar(0, 0, 255), 1);
  const std::string text = "frame " + std::to_string(r.index) + "  boxes " + std::to_string(r.person_boxes) +
                           "  kept " + std::to_string(r.kept_keypoints.size()) + "  removed " +
                           std::to_string(r.removed_keypoints.size()) + "  budget " +
                           std::to_string(r.feature_budget) + "  " + tracking::to_string(r.state);
  cv::putText(canvas, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 2);
  cv::putText(canvas, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1);
  return canvas;
}

nlohmann::json frame_json(const FrameReport& r) {
  return {{"index", r.index},
          {"person_boxes", r.person_boxes},
          {"people_area", r.people_area},
          {"keypoints_before_filter", r.keypoints_before_filter},
          {"detector_ms", r.detector_ms},
          {"detector_wait_ms", r.detector_wait_ms},
          {"stereo_matches", r.stereo_matches},
          {"right_keypoints_removed", r.right_keypoints_removed},
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
          {"keyframe", r.new_keyframe}};
}

// Stereo: raw EuRoC pairs without LEFT/RIGHT blocks are rectified from the dataset's sensor.yaml
// calibration; otherwise the images must already be rectified (no distortion).
void prepare_stereo_settings(const io::FrameSource& source, io::Settings& settings) {
  if (settings.rectification) return;
  if (const auto* euroc = dynamic_cast<const io::EurocDataset*>(&source)) {
    const auto right = euroc->right_calibration();
    const auto right_from_left = euroc->right_from_left();
    assert(right && right_from_left);  // a stereo EuRoC dataset has cam1
    const std::string where = source.path() + " (cam0/cam1 sensor.yaml)";
    apply_rectification(settings, rectification_from_euroc(euroc->left_calibration(), *right, *right_from_left, where));
    spdlog::info("stereo rectification computed from {}: fx {:.3f}, bf {:.4f}", where, settings.camera.fx,
                 settings.camera.bf);
    return;
  }
  const auto& c = settings.camera;
  if (c.k1 != 0 || c.k2 != 0 || c.p1 != 0 || c.p2 != 0 || c.k3 != 0) {
    throw input_error(settings.path, "Camera.k1/k2/p1/p2/k3: stereo images must be rectified, but the camera has "
                                     "distortion and the settings have no LEFT/RIGHT rectification blocks");
  }
}

}  // namespace

RunSummary run_sequence(const RunOptions& options) {
  auto source = io::open_source(options.dataset);
  const io::SensorKind sensor = options.sensor.value_or(source->sensor());
  if (sensor == io::SensorKind::kRgbd && source->sensor() != io::SensorKind::kRgbd) {
    throw InputError(options.dataset + ": --sensor rgbd needs a dataset with depth images");
  }
  if (sensor == io::SensorKind::kStereo && source->sensor() != io::SensorKind::kStereo) {
    throw InputError(options.dataset + ": --sensor stereo needs a stereo dataset (EuRoC with cam1, KITTI with "
                     "image_1); this one is " + io::to_string(source->sensor()));
  }
  std::string settings_path = options.settings_path;
  if (settings_path.empty()) settings_path = source->default_settings_path();
  if (settings_path.empty()) {
    throw InputError(options.dataset + ": no settings given (--settings) and the dataset has no settings.yaml");
  }
  const io::Settings settings = io::load_settings(settings_path, sensor);
  if (options.out_dir.empty()) throw InputError("--out: output directory required");

  io::Settings run_settings = settings;
  if (!options.filter_mode.empty()) {
    run_settings.people_filter.mode = options.filter_mode;
    run_settings.check(sensor);
  }
  if (sensor == io::SensorKind::kStereo) prepare_stereo_settings(*source, run_settings);
  SystemOptions system_options;
  system_options.sensor = sensor;
  system_options.sequential = options.sequential;
  system_options.people_filter = options.people_filter;
  system_options.detections_file = options.detections_file;
  system_options.detector_model = options.detector_model;
  system_options.record_keypoints = options.save_frames > 0;
  system_options.vocabulary_path = options.vocabulary;
  system_options.loop_closing = options.loop_closing;
  System slam(run_settings, system_options);
  std::vector<std::pair<size_t, std::vector<uchar>>> saved_frames;  // encoded JPEGs, written at the end

  std::vector<FrameReport> reports;
  std::vector<double> load_ms;  // time tracking waited for the next decoded frame
  const auto run_start = std::chrono::steady_clock::now();
  const size_t expected = source->summary().frames.value_or(0);
  FramePrefetcher prefetcher(*source, 3, options.max_frames);
  while (true) {
    const auto load_start = std::chrono::steady_clock::now();
    auto frame = prefetcher.next();
    if (!frame) break;
    load_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - load_start).count());
    reports.push_back(slam.track(frame->images, frame->info.timestamp_s));
    if (options.save_frames > 0 && reports.back().index % options.save_frames == 0) {
      std::vector<uchar> jpeg;
      cv::imencode(".jpg", draw_frame(frame->images.colour, reports.back()), jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
      saved_frames.emplace_back(reports.back().index, std::move(jpeg));
      reports.back().kept_keypoints.clear();
      reports.back().removed_keypoints.clear();
    }
    if (options.progress && reports.size() % 100 == 0) {
      spdlog::info("frame {}/{}: {} keyframes, {} map points", reports.size(), expected, slam.num_keyframes(),
                   slam.num_map_points());
    }
  }
  slam.shutdown();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start).count();
  if (reports.empty()) throw InputError(options.dataset + ": no frames");

  RunSummary summary;
  summary.frames = reports.size();
  std::vector<double> tracking_ms, extraction_ms, total_ms, detector_ms, detector_wait_ms;
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& r : reports) {
    if (r.state == tracking::TrackingState::kOk) ++summary.tracked;
    if (!summary.init_frame && r.method == "init") summary.init_frame = r.index;
    tracking_ms.push_back(r.tracking_ms);
    extraction_ms.push_back(r.extraction_ms);
    total_ms.push_back(r.extraction_ms + r.detector_wait_ms + r.tracking_ms);
    detector_ms.push_back(r.detector_ms);
    detector_wait_ms.push_back(r.detector_wait_ms);
    frames.push_back(frame_json(r));
  }
  summary.tracked_percent = 100.0 * static_cast<double>(summary.tracked) / static_cast<double>(summary.frames);
  if (sensor == io::SensorKind::kMonocular && !summary.init_frame) {
    spdlog::warn("{}: monocular map never initialised in {} frames (needs a textured scene and a camera that "
                 "translates, not only rotates)",
                 options.dataset, summary.frames);
  }
  summary.throughput_fps = static_cast<double>(summary.frames) / wall_s;
  summary.tracking_ms_median = percentile(tracking_ms, 0.5);
  summary.tracking_ms_p95 = percentile(tracking_ms, 0.95);
  summary.extraction_ms_median = percentile(extraction_ms, 0.5);
  summary.total_ms_median = percentile(total_ms, 0.5);
  summary.total_ms_p95 = percentile(total_ms, 0.95);

  const io::Trajectory camera_trajectory = slam.camera_trajectory();
  const io::Trajectory keyframe_trajectory = slam.keyframe_trajectory();
  const auto mapper = slam.mapper_stats();

  nlohmann::json accuracy = nullptr;
  const io::Trajectory& ground_truth = source->ground_truth();
  if (!ground_truth.empty() && camera_trajectory.size() >= 3) {
    try {
      // Monocular trajectories have an arbitrary scale: Sim3 alignment, and RPE at the aligned scale.
      const bool monocular = sensor == io::SensorKind::kMonocular;
      eval::AteOptions ate_options;
      ate_options.alignment = monocular ? eval::Alignment::kSim3 : eval::Alignment::kSe3;
      const auto ate = eval::evaluate_ate(ground_truth, camera_trajectory, ate_options, "ground truth",
                                          "camera trajectory");
      summary.ate_rmse_m = ate.translation_error_m.rmse;
      accuracy = {{"ate_rmse_m", ate.translation_error_m.rmse},
                  {"ate_mean_m", ate.translation_error_m.mean},
                  {"ate_median_m", ate.translation_error_m.median},
                  {"ate_max_m", ate.translation_error_m.max},
                  {"ate_pairs", ate.matches.size()},
                  {"alignment", eval::to_string(ate_options.alignment)}};
      if (monocular) accuracy["sim3_scale"] = ate.alignment.scale;
      eval::RpeOptions rpe_options;
      if (monocular) rpe_options.scale = ate.alignment.scale;
      const auto rpe = eval::evaluate_rpe(ground_truth, camera_trajectory, rpe_options, "ground truth",
                                          "camera trajectory");
      summary.rpe_trans_rmse_m = rpe.translation_error_m.rmse;
      accuracy["rpe_trans_rmse_m_per_s"] = rpe.translation_error_m.rmse;
      accuracy["rpe_rot_rmse_deg_per_s"] = rpe.rotation_error_deg.rmse;
    } catch (const InputError& e) {
      spdlog::warn("accuracy not evaluated: {}", e.what());
    }
  }

  nlohmann::json doc;
  doc["dataset"] = options.dataset;
  doc["settings"] = settings_path;
  doc["sensor"] = io::to_string(sensor);
  doc["mode"] = options.sequential ? "sequential" : "threaded";
  if (const auto& vocabulary = slam.vocabulary_info()) {
    doc["vocabulary"] = {{"path", vocabulary->path}, {"words", vocabulary->words}, {"load_ms", vocabulary->load_ms}};
  } else {
    doc["vocabulary"] = nullptr;
  }
  doc["people_filter"] = slam.people_filter_enabled()
                             ? nlohmann::json{{"detector", slam.detector_name()},
                                              {"mode", run_settings.people_filter.mode},
                                              {"margin_px", run_settings.people_filter.margin_px},
                                              {"filter_before_nms", run_settings.detector.filter_before_nms},
                                              {"feature_budget", run_settings.feature_budget.enabled},
                                              {"area", run_settings.feature_budget.area},
                                              {"detector_ms_median", percentile(detector_ms, 0.5)},
                                              {"detector_wait_ms_median", percentile(detector_wait_ms, 0.5)},
                                              {"detector_wait_ms_p95", percentile(detector_wait_ms, 0.95)}}
                             : nlohmann::json(nullptr);
  doc["summary"] = {{"frames", summary.frames},
                    {"tracked_frames", summary.tracked},
                    {"tracked_percent", summary.tracked_percent},
                    {"init_frame", summary.init_frame ? nlohmann::json(*summary.init_frame) : nlohmann::json(nullptr)},
                    {"wall_time_s", wall_s},
                    {"throughput_fps", summary.throughput_fps},
                    {"tracking_ms_median", summary.tracking_ms_median},
                    {"tracking_ms_p95", summary.tracking_ms_p95},
                    {"extraction_ms_median", summary.extraction_ms_median},
                    {"total_ms_median", summary.total_ms_median},
                    {"total_ms_p95", summary.total_ms_p95},
                    {"load_wait_ms_median", percentile(load_ms, 0.5)},
                    {"keyframes", slam.num_keyframes()},
                    {"map_points", slam.num_map_points()},
                    {"map_resets", slam.map_resets()}};
  doc["local_mapping"] = {{"keyframes_processed", mapper.keyframes_processed},
                          {"points_created", mapper.points_created},
                          {"points_culled", mapper.points_culled},
                          {"keyframes_culled", mapper.keyframes_culled},
                          {"ba_runs", mapper.ba_runs},
                          {"ba_aborted", mapper.ba_aborted},
                          {"ba_ms_mean", mapper.ba_runs > 0 ? mapper.ba_time_ms_total / mapper.ba_runs : 0.0},
                          {"register_ms_mean", mapper.register_ms_total / std::max(1, mapper.keyframes_processed)},
                          {"triangulation_ms_mean", mapper.triangulation_ms_total / std::max(1, mapper.keyframes_processed)},
                          {"fusion_ms_mean", mapper.fusion_ms_total / std::max(1, mapper.keyframes_processed)},
                          {"culling_ms_mean", mapper.culling_ms_total / std::max(1, mapper.keyframes_processed)},
                          {"keyframe_ms_mean", mapper.processing_ms_total / std::max(1, mapper.keyframes_processed)}};
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
  doc["frames"] = std::move(frames);
  summary.json = doc;

  // Outputs, only now that everything succeeded.
  const std::filesystem::path out(options.out_dir);
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) throw input_error(options.out_dir, "cannot create output directory: " + ec.message());
  const auto format = parse_format(settings.output.trajectory_format);
  io::write_trajectory((out / "CameraTrajectory.txt").string(), camera_trajectory, format);
  io::write_trajectory((out / "KeyFrameTrajectory.txt").string(), keyframe_trajectory, format);
  if (!saved_frames.empty()) {
    const auto frames_dir = out / "frames";
    std::filesystem::create_directories(frames_dir, ec);
    if (ec) throw input_error(frames_dir.string(), "cannot create directory: " + ec.message());
    for (const auto& [index, jpeg] : saved_frames) {
      char name[32];
      std::snprintf(name, sizeof name, "%06zu.jpg", index);
      AtomicFile file(frames_dir / name);
      file.stream().write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
      file.commit();
    }
  }
  write_file_atomic(out / "run.json", doc.dump(1) + "\n");
  return summary;
}

}  // namespace crowdslam::system
