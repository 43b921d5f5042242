#include "crowdslam/run/run_sequence.h"

#include <spdlog/spdlog.h>

#include <cassert>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "crowdslam/io/euroc_dataset.h"
#include "crowdslam/io/euroc_rectification.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/journal/output_dir.h"
#include "crowdslam/journal/run_journal.h"
#include "crowdslam/report/run_report.h"
#include "crowdslam/run/filter_mask_score.h"
#include "crowdslam/run/frame_prefetcher.h"
#include "crowdslam/run/input_checks.h"
#include "crowdslam/run/map_files.h"
#include "crowdslam/run/run_document.h"
#include "crowdslam/run/sensor_pacer.h"
#include "crowdslam/run/viewer_session.h"
#include "crowdslam/system/system.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/interrupt.h"
#include "crowdslam/util/progress.h"
#include "crowdslam/util/text.h"

namespace crowdslam::run {

namespace {

using Clock = std::chrono::steady_clock;

// Stereo: raw EuRoC pairs without LEFT/RIGHT blocks are rectified from the dataset's sensor.yaml
// calibration; otherwise the images must already be rectified (no distortion).
void prepare_stereo_settings(const io::FrameSource& source, io::Settings& settings) {
  if (settings.rectification) return;
  if (const auto* euroc = dynamic_cast<const io::EurocDataset*>(&source)) {
    const auto right = euroc->right_calibration();
    const auto right_from_left = euroc->right_from_left();
    assert(right && right_from_left);  // a stereo EuRoC dataset has cam1
    const std::string where = source.path() + " (cam0/cam1 sensor.yaml)";
    io::apply_rectification(settings,
                            io::rectification_from_euroc(euroc->left_calibration(), *right, *right_from_left, where));
    spdlog::info("stereo rectification computed from {}: fx {:.3f}, bf {:.4f}", where, settings.camera.fx,
                 settings.camera.bf);
    return;
  }
  const auto& c = settings.camera;
  if (c.k1 != 0 || c.k2 != 0 || c.p1 != 0 || c.p2 != 0 || c.k3 != 0) {
    throw input_error(settings.path,
                      "Camera.k1/k2/p1/p2/k3: stereo images must be rectified, but the camera has "
                      "distortion and the settings have no LEFT/RIGHT rectification blocks");
  }
}

system::SystemOptions system_options(const RunOptions& options, io::SensorKind sensor) {
  system::SystemOptions s;
  s.sensor = sensor;
  s.sequential = options.sequential;
  s.people_filter = options.people_filter;
  s.detections_file = options.detections_file;
  s.detector_model = options.detector_model;
  // Drawn by the journal / the viewer; scored against the person masks.
  s.record_keypoints = options.save_frames > 0 || options.viewer || options.score_filter;
  s.vocabulary_path = options.vocabulary;
  s.loop_closing = options.loop_closing;
  s.background_nice = options.background_nice;
  s.prepare_detection = !options.pace_sensor;  // a paced run drops frames: no detection before their turn
  s.replay_waits_for_mapping = !options.pace_sensor;  // a paced replay is a live camera: it does not wait
  return s;
}

// Everything checked before any output exists: settings, sensor, options.
struct Prepared {
  std::unique_ptr<io::FrameSource> source;
  io::SensorKind sensor = io::SensorKind::kRgbd;
  std::string settings_path;
  io::Settings settings;      // as read
  io::Settings run_settings;  // with the options applied
};

Prepared prepare(const RunOptions& options) {
  Prepared p;
  io::DatasetOptions dataset_options;
  dataset_options.missing_images_ok = options.skip_bad_frames;  // skipped like any unreadable frame
  p.source = io::open_source(options.dataset, dataset_options);
  if (const auto frames = p.source->summary().frames; frames && *frames == 0) {
    throw InputError(clip_text(options.dataset) + ": no frames");
  }
  p.settings_path = options.settings_path.empty() ? p.source->default_settings_path() : options.settings_path;
  if (p.settings_path.empty()) {
    throw InputError(clip_text(options.dataset) +
                     ": no settings given (--settings) and the dataset has no settings.yaml");
  }
  check_requested_sensor(*p.source, options.sensor);
  p.settings = io::load_settings(p.settings_path, options.sensor.value_or(p.source->sensor()));
  p.sensor = choose_sensor(*p.source, p.settings, options.sensor);
  p.run_settings = p.settings;
  if (!options.filter_mode.empty()) {
    if (options.filter_mode != "paper" && options.filter_mode != "depth") {
      throw InputError("--filter-mode: expected 'paper' or 'depth', got '" +
                       clip_text(options.filter_mode, 60) + "'");
    }
    p.run_settings.people_filter.mode = options.filter_mode;
  }
  if (!options.detector_mode.empty()) {
    if (options.detector_mode != "every_frame" && options.detector_mode != "latest") {
      throw InputError("--detector-mode: expected 'every_frame' or 'latest', got '" +
                       clip_text(options.detector_mode, 60) + "'");
    }
    p.run_settings.detector.mode = options.detector_mode;
  }
  if (options.detector_interval != 0) {
    if (options.detector_interval < 1) {
      throw InputError("--detector-interval: expected a number of frames >= 1, got " +
                       std::to_string(options.detector_interval));
    }
    p.run_settings.detector.latest_interval = options.detector_interval;
  }
  if (!options.box_tracker.empty()) {
    if (options.box_tracker != "on" && options.box_tracker != "off") {
      throw InputError("--box-tracker: expected 'on' or 'off', got '" + clip_text(options.box_tracker, 60) +
                       "'");
    }
    p.run_settings.detector.tracker = options.box_tracker == "on";
  }
  if (!options.geometry.empty()) {
    if (options.geometry != "on" && options.geometry != "off") {
      throw InputError("--geometry: expected 'on' or 'off', got '" + clip_text(options.geometry, 60) + "'");
    }
    p.run_settings.geometry.dynamic_check = options.geometry == "on";
  }
  if (!options.ground.empty()) {
    if (options.ground != "on" && options.ground != "off") {
      throw InputError("--ground: expected 'on' or 'off', got '" + clip_text(options.ground, 60) + "'");
    }
    p.run_settings.ground.enabled = options.ground == "on";
  }
  if (p.sensor == io::SensorKind::kStereo) prepare_stereo_settings(*p.source, p.run_settings);
  // Refused before the vocabulary loads; its rows are read and checked when the system is built (also
  // before any output).
  if (!options.detections_file.empty()) check_regular_file(options.detections_file);
  check_first_frame(*p.source, p.settings, options.skip_bad_frames);
  return p;
}

void write_final_outputs(const std::filesystem::path& out, const system::System& slam,
                         io::TrajectoryFormat format, const nlohmann::json& doc) {
  io::write_trajectory((out / "CameraTrajectory.txt").string(), slam.camera_trajectory(), format);
  io::write_trajectory((out / "KeyFrameTrajectory.txt").string(), slam.keyframe_trajectory(), format);
  // Frames bridged while people hid the view: not tracked, so never in CameraTrajectory.txt.
  const io::Trajectory bridged = slam.bridged_trajectory();
  if (!bridged.empty()) io::write_trajectory((out / "BridgedTrajectory.txt").string(), bridged, format);
  // Replaced, never thrown: a path or an error message may hold bytes that are not UTF-8.
  write_file_atomic(out / "run.json", doc.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

// What the progress line shows after the counts: state, tracked frames, keyframes, map points, people.
std::string progress_detail(const system::System& slam, const system::FrameReport& report) {
  char detail[160];
  std::snprintf(detail, sizeof detail, "%s  tracked %zu  keyframes %zu  points %zu  people %.0f %%",
                tracking::to_string(report.state), slam.tracked_frames(), slam.num_keyframes(),
                slam.num_map_points(), 100.0 * report.people_area);
  return detail;
}
// A signal after the last frame (while the threads stop or the map is saved) still ends the run as
// interrupted: it was asked to stop, and run.json and the exit code say so.
void note_late_signal(system::EndState& end) {
  if (!end.completed() || interrupt_signal() == 0) return;
  end.kind = system::EndState::Kind::kInterrupted;
  end.signal = interrupt_signal();
  spdlog::warn("run interrupted by {} after its last frame; writing the outputs", signal_name(end.signal));
}
}  // namespace

RunSummary run_sequence(const RunOptions& options) {
  journal::check_output_dir(options.out_dir, options.overwrite);  // before anything is read
  check_map_options(options);
  Prepared p = prepare(options);
  // A dataset without person masks fails before any output (and before the system starts its threads).
  std::optional<FilterMaskScore> filter_score;
  if (options.score_filter) filter_score.emplace(std::filesystem::path(options.dataset) / "people_mask");
  system::System slam(p.run_settings, system_options(options, p.sensor));
  nlohmann::json map_json = load_map_if_requested(options, slam);  // a bad map fails before any output
  std::unique_ptr<ViewerSession> viewer;  // a port in use fails before any output too
  if (options.viewer) {
    ViewerSessionOptions viewer_options;
    viewer_options.host = options.viewer_host;
    viewer_options.port = options.viewer_port;
    viewer_options.ground_truth = p.source->ground_truth();
    viewer_options.monocular = p.sensor == io::SensorKind::kMonocular;
    viewer_options.pause_timeout_s = options.viewer_pause_timeout_s;
    viewer = std::make_unique<ViewerSession>(viewer_options);
  }

  // From here on the run has outputs: the directory, run.json saying "running", the journal.
  const std::filesystem::path out(options.out_dir);
  std::error_code ec;
  const bool created = !std::filesystem::exists(out, ec);
  const auto removed = journal::prepare_output_dir(out, options.overwrite);
  if (!removed.empty())
    spdlog::info("{}: replaced the earlier run ({} entries)", clip_text(options.out_dir), removed.size());
  const auto format = io::parse_trajectory_format(p.settings.output.trajectory_format);
  journal::RunJournalOptions journal_options;
  journal_options.out_dir = out;
  journal_options.format = format;
  journal_options.save_every = options.save_frames;
  journal_options.flush_every_poses = options.journal_flush_frames;
  std::unique_ptr<journal::RunJournal> journal_ptr;
  try {
    write_file_atomic(out / "run.json", running_document(options, p.settings_path, p.sensor)
                                            .dump(1, ' ', false, nlohmann::json::error_handler_t::replace) +
                                            "\n");
    journal_ptr = std::make_unique<journal::RunJournal>(journal_options);
  } catch (...) {  // nothing was run yet: leave nothing behind
    if (created) {
      remove_quietly(out);
    } else {
      for (const char* name : {"run.json", "CameraTrajectory.txt", "frames"}) remove_quietly(out / name);
    }
    throw;
  }
  journal::RunJournal& journal = *journal_ptr;
  slam.add_observer(&journal);
  if (viewer) slam.add_observer(&viewer->observer());
  for (auto* observer : options.observers) slam.add_observer(observer);
  if (filter_score) slam.add_observer(&*filter_score);

  InputMonitor monitor(p.run_settings, p.sensor);
  std::vector<system::FrameReport> reports;
  std::vector<double> load_ms;  // time tracking waited for the next decoded frame
  system::EndState end;
  std::exception_ptr error;
  const auto run_start = Clock::now();
  const size_t expected = p.source->summary().frames.value_or(0);
  // The reader thread also starts each frame's extraction and detection (System::prepare).
  FramePrefetcher prefetcher(*p.source, 3, options.max_frames, options.skip_bad_frames,
                             [&slam](const io::FrameImages& images) { return slam.prepare(images); });
  std::optional<SensorPacer> pacer;
  size_t dropped_after_tracking = 0;
  if (options.pace_sensor) pacer.emplace();
  const size_t progress_total = options.max_frames > 0 && (expected == 0 || options.max_frames < expected)
                                    ? options.max_frames
                                    : expected;
  ProgressLine progress(options.progress, progress_total, "frame");
  try {
    while (true) {
      if (const int signal = interrupt_signal()) {
        end.kind = system::EndState::Kind::kInterrupted;
        end.signal = signal;
        break;
      }
      if (viewer) {
        const auto paused = viewer->wait_while_paused();
        if (pacer) pacer->shift(paused);  // a pause stops the sensor's clock too
        viewer->set_progress(reports.size(), false);
        if (interrupt_signal()) continue;  // handled at the top of the loop
      }
      const auto load_start = Clock::now();
      auto prefetched = prefetcher.next();
      if (!prefetched) break;
      io::Frame* frame = &prefetched->frame;
      load_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - load_start).count());
      if (pacer && !pacer->admit(frame->info.timestamp_s)) {  // arrived while tracking was busy: dropped
        if (slam.tracked_frames() > 0) ++dropped_after_tracking;
        continue;
      }
      monitor.check_frame(*frame);
      reports.push_back(slam.track(frame->images, frame->info.timestamp_s, prefetched->prepared.get()));
      auto& report = reports.back();
      monitor.after_tracking(*frame, report.keypoints_before_filter);
      // Drawn by the journal (it copied what it needs): run.json does not keep them.
      // (swap, not `= {}`: that keeps the capacity, 40 MB over bonn_crowd's 927 frames).
      std::vector<cv::KeyPoint>().swap(report.kept_keypoints);
      std::vector<cv::KeyPoint>().swap(report.removed_keypoints);
      std::vector<people::PersonBox>().swap(report.boxes);
      journal.check();
      // A line redrawn in place, or a plain line in logs and CI (the detail takes the map's lock: only then).
      if (progress.due(reports.size())) progress.update(reports.size(), progress_detail(slam, report));
    }
  } catch (const std::exception& e) {
    end.kind = system::EndState::Kind::kFailed;
    end.reason = e.what();
    error = std::current_exception();
  }
  progress.finish(reports.size(), reports.empty() ? std::string() : progress_detail(slam, reports.back()));
  const double wall_s = std::chrono::duration<double>(Clock::now() - run_start).count();
  prefetcher.cancel();
  // From here the outputs are written: a second signal no longer exits at once, which would leave run.json
  // "running" (a third one does).
  const FinishingScope finishing;
  slam.finish(end);  // stops the threads; the journal drains and closes
  if (end.kind != system::EndState::Kind::kFailed) {
    try {
      journal.check();
    } catch (const std::exception& e) {
      end.kind = system::EndState::Kind::kFailed;
      end.reason = e.what();
      error = std::current_exception();
    }
  }
  if (end.kind == system::EndState::Kind::kInterrupted) {
    spdlog::warn("run interrupted by {} after {} frames; writing the outputs", signal_name(end.signal),
                 reports.size());
  }
  if (viewer) {
    viewer->set_progress(reports.size(), true);
    viewer->stop();
  }
  add_localization_stats(reports, map_json);
  note_late_signal(end);
  try {
    save_map_if_requested(options, slam, end.to_string(), map_json);
  } catch (const std::exception& e) {
    if (map_json.is_object()) map_json["save_error"] = e.what();
    if (end.kind != system::EndState::Kind::kFailed) {
      end.kind = system::EndState::Kind::kFailed;
      end.reason = e.what();
      error = std::current_exception();
    }
  }

  RunSummary summary;
  summary.out_dir = options.out_dir;
  summary.frames = reports.size();
  summary.tracked = slam.tracked_frames();
  summary.tracked_percent =
      summary.frames > 0 ? 100.0 * static_cast<double>(summary.tracked) / static_cast<double>(summary.frames)
                         : 0.0;
  summary.throughput_fps = wall_s > 0 ? static_cast<double>(summary.frames) / wall_s : 0.0;
  summary.segments = slam.segments();
  summarise_frames(reports, summary);
  monitor.warn_totals();
  if (p.sensor == io::SensorKind::kMonocular && !summary.init_frame && summary.frames > 0 &&
      options.load_map.empty()) {  // a loaded map needs no initialisation
    spdlog::warn(
        "{}: monocular map never initialised in {} frames (needs a textured scene and a camera that "
        "translates, not only rotates)",
        clip_text(options.dataset), summary.frames);
  }
  note_late_signal(end);
  const bool untracked = end.completed() && summary.tracked == 0 && !options.allow_untracked;
  if (untracked) {
    end.kind = system::EndState::Kind::kFailed;
    end.reason = "no frame was tracked (0 of " + std::to_string(summary.frames) + ")";
  }
  summary.end = end;

  nlohmann::json accuracy = nullptr;
  const auto ground_truth_name = p.source->summary().ground_truth_path;
  evaluate_accuracy(p.source->ground_truth(),
                    ground_truth_name.empty() ? "ground truth" : clip_text(ground_truth_name),
                    slam.camera_trajectory_segments(), slam.bridged_trajectory_segments(), summary.segments, slam.keyframe_trajectory(),
                    p.sensor == io::SensorKind::kMonocular, summary, accuracy);
  const SkippedFrames skipped = prefetcher.skipped();
  nlohmann::json input = monitor.to_json();
  input["pace"] = pacer ? "sensor" : "none";
  input["dropped_frames"] = pacer ? pacer->dropped() : 0;
  input["dropped_after_first_tracked"] = dropped_after_tracking;
  if (pacer && pacer->dropped() > 0) {
    spdlog::info(
        "--pace sensor: {} frames dropped because tracking was busy when they arrived ({} after the first "
        "tracked frame)",
        pacer->dropped(), dropped_after_tracking);
  }
  input["skipped_frames"] = skipped.count;
  input["first_skipped_error"] =
      skipped.first_error.empty() ? nlohmann::json(nullptr) : nlohmann::json(skipped.first_error);
  if (skipped.count > 1)
    spdlog::warn("{} unreadable frames skipped (first: {})", skipped.count, skipped.first_error);
  const RunContext context{options,  p.settings_path,
                           p.sensor, p.run_settings,
                           slam,     wall_s,
                           load_ms,  input,
                           map_json, filter_score ? filter_score->to_json() : nlohmann::json(nullptr)};
  summary.json = final_document(context, reports, summary, accuracy);
  write_final_outputs(out, slam, format, summary.json);
  report::write_run_report(out, summary.json);  // never fails the run: logged, recorded in run.json

  if (error) {
    const std::string where = " (the " + std::to_string(summary.tracked) +
                              " frames tracked before it are in " + clip_text(options.out_dir) +
                              ", run.json says \"failed\")";
    try {
      std::rethrow_exception(error);
    } catch (const InputError& e) {
      throw InputError(std::string(e.what()) + where);
    }
  }
  if (untracked) {
    throw InputError(clip_text(options.dataset) + ": " + end.reason + "; outputs are in " +
                     clip_text(options.out_dir) + " (--allow-untracked accepts such a run)");
  }
  return summary;
}

}  // namespace crowdslam::run
