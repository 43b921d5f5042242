#include "crowdslam/system/run_sequence.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/eval/ate.h"
#include "crowdslam/eval/rpe.h"
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

}  // namespace

RunSummary run_sequence(const RunOptions& options) {
  auto source = io::open_source(options.dataset);
  const io::SensorKind sensor = options.sensor.value_or(source->sensor());
  if (sensor == io::SensorKind::kRgbd && source->sensor() != io::SensorKind::kRgbd) {
    throw InputError(options.dataset + ": --sensor rgbd needs a dataset with depth images");
  }
  if (sensor != io::SensorKind::kRgbd) {
    throw InputError(options.dataset + ": sensor '" + io::to_string(sensor) +
                     "' is not supported yet (RGB-D only in this version)");
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
  SystemOptions system_options;
  system_options.sensor = sensor;
  system_options.sequential = options.sequential;
  system_options.people_filter = options.people_filter;
  system_options.detections_file = options.detections_file;
  system_options.detector_model = options.detector_model;
  system_options.record_keypoints = options.save_frames > 0;
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
    tracking_ms.push_back(r.tracking_ms);
    extraction_ms.push_back(r.extraction_ms);
    total_ms.push_back(r.extraction_ms + r.detector_wait_ms + r.tracking_ms);
    detector_ms.push_back(r.detector_ms);
    detector_wait_ms.push_back(r.detector_wait_ms);
    frames.push_back(frame_json(r));
  }
  summary.tracked_percent = 100.0 * static_cast<double>(summary.tracked) / static_cast<double>(summary.frames);
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
      const auto ate = eval::evaluate_ate(ground_truth, camera_trajectory, eval::AteOptions{}, "ground truth",
                                          "camera trajectory");
      summary.ate_rmse_m = ate.translation_error_m.rmse;
      accuracy = {{"ate_rmse_m", ate.translation_error_m.rmse},
                  {"ate_mean_m", ate.translation_error_m.mean},
                  {"ate_median_m", ate.translation_error_m.median},
                  {"ate_max_m", ate.translation_error_m.max},
                  {"ate_pairs", ate.matches.size()},
                  {"alignment", "se3"}};
      const auto rpe = eval::evaluate_rpe(ground_truth, camera_trajectory, eval::RpeOptions{}, "ground truth",
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
