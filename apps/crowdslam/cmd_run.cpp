// `crowdslam run`: SLAM over a sequence, with outputs in --out (kept as a journal while it runs).
#include <spdlog/spdlog.h>

#include <iostream>

#include "commands.h"
#include "crowdslam/io/dataset.h"
#include "crowdslam/run/run_sequence.h"
#include "crowdslam/util/interrupt.h"

namespace crowdslam::app {

namespace {
struct RunArgs {
  run::RunOptions options;
  std::string sensor;
  std::string pace = "none";
  size_t frames = 0;
};

// A count (frames): digits only, so that -1 is an error rather than a huge number.
CLI::Validator count() {
  return CLI::Validator(
      [](std::string& value) {
        return !value.empty() && value.size() <= 12 && value.find_first_not_of("0123456789") == std::string::npos
                   ? std::string()
                   : "expected a whole number >= 0, got '" + value.substr(0, 40) + "'";
      },
      "", "COUNT");
}

CLI::Validator non_empty() {
  return CLI::Validator([](std::string& value) { return value.empty() ? std::string("empty value") : std::string(); },
                        "", "NON-EMPTY");
}

void print_summary(const run::RunSummary& summary) {
  std::cout << "end state         " << summary.end.to_string() << "\n"
            << "frames            " << summary.frames << "\n"
            << "tracked           " << summary.tracked << " (" << summary.tracked_percent << " %)\n"
            << "throughput        " << summary.throughput_fps << " frames/s\n"
            << "tracking ms       median " << summary.tracking_ms_median << ", p95 "
            << summary.tracking_ms_p95 << "\n"
            << "extraction ms     median " << summary.extraction_ms_median << "\n";
  if (summary.bridged > 0) {
    std::cout << "bridged           " << summary.bridged
              << " (people hid the view; motion-model poses in BridgedTrajectory.txt)\n";
  }
  if (summary.init_frame) std::cout << "initialised at    frame " << *summary.init_frame << "\n";
  if (summary.segments.size() > 1) {
    std::cout << "maps              " << summary.segments.size() << " (the map was reset "
              << summary.segments.size() - 1 << " times; every tracked frame is in CameraTrajectory.txt)\n";
  }
  if (summary.ate_rmse_m) {
    std::cout << "ATE RMSE          " << *summary.ate_rmse_m << " m";
    if (summary.segments.size() > 1 && summary.evaluated_map_id) {
      size_t poses = 0;
      for (const auto& a : summary.segment_accuracy) {
        if (a.map_id == *summary.evaluated_map_id) poses = a.poses;
      }
      std::cout << " (map " << *summary.evaluated_map_id << ", the longest: " << poses << " of "
                << summary.tracked << " poses; each map in run.json)";
    }
    std::cout << "\n";
  }
  const auto& accuracy = summary.json["accuracy"];
  if (accuracy.is_object() && accuracy.contains("sim3_scale")) {
    std::cout << "ATE alignment     sim3 (scale " << accuracy["sim3_scale"].get<double>() << ")\n";
  }
  if (accuracy.is_object() && accuracy.contains("ate_keyframes_rmse_m")) {
    std::cout << "ATE keyframes     " << accuracy["ate_keyframes_rmse_m"].get<double>() << " m ("
              << accuracy["ate_keyframes_poses"].get<size_t>() << " keyframes, aligned on their own)\n";
  }
  if (summary.rpe_trans_rmse_m) std::cout << "RPE trans RMSE    " << *summary.rpe_trans_rmse_m << " m/s\n";
  std::cout << "outputs           " << summary.out_dir
            << "/{CameraTrajectory.txt,KeyFrameTrajectory.txt,run.json,report.html}\n";
}
}  // namespace

void add_run_command(CLI::App& app, GlobalOptions& global) {
  auto args = std::make_shared<RunArgs>();
  auto* cmd = app.add_subcommand("run", "Run SLAM on a dataset and write trajectories and statistics");
  cmd->add_option("--dataset,-d", args->options.dataset,
                  "Dataset directory (TUM/Bonn, EuRoC, KITTI, images), video or camera index")
      ->required();
  cmd->add_option("--settings,-s", args->options.settings_path,
                  "Settings YAML (default: DATASET/settings.yaml)");
  cmd->add_option("--out,-o", args->options.out_dir, "Output directory (new or empty; see --overwrite)")
      ->required();
  cmd->add_flag("--overwrite", args->options.overwrite, "Replace an earlier run's outputs in --out");
  cmd->add_option("--sensor", args->sensor,
                  "Override the sensor detected from the dataset: rgbd, stereo or mono (mono: the colour / "
                  "left images only)");
  cmd->add_flag("--sequential", args->options.sequential,
                "Local mapping inline after each frame (reproducible); default: threaded");
  cmd->add_option(
         "--background-nice", args->options.background_nice,
         "Local mapping and loop closing run this much nicer than tracking (0-19, default 0: the same "
         "priority). On a machine the run saturates, the frame's path then gets the cores first and "
         "the mapper makes fewer keyframes (docs/PROFILE.md)")
      ->check(CLI::Range(0, 19));
  cmd->add_option("--frames", args->frames, "Process only the first N frames (0 = all)")
      ->check(count());
  cmd->add_flag(
      "!--no-people-filter", args->options.people_filter,
      "Run without the people filter and without the feature-number update (static-world baseline)");
  cmd->add_option("--detections", args->options.detections_file,
                  "Person boxes from a MOT-format file (frame,id,x,y,w,h,conf,...) instead of the detector");
  cmd->add_option("--detector", args->options.detector_model,
                  "Detector model: body, coco, yolox, bytetrack, PATH.cfg or PATH.onnx (input, backend and "
                  "preprocessing from the Detector.* settings; docs/DETECTION.md)");
  cmd->add_option("--filter-mode", args->options.filter_mode, "People filter mode: paper or depth");
  cmd->add_option(
      "--detector-mode", args->options.detector_mode,
      "every_frame: each frame waits for its own boxes; latest: the detector takes the newest frame "
      "when free and other frames get its boxes moved by the image flow (Detector.mode)");
  cmd->add_option("--detector-interval", args->options.detector_interval,
                  "latest mode: offer the detector a frame at most every N frames (1 = whenever it is free; "
                  "Detector.latest_interval)");
  cmd->add_option(
      "--box-tracker", args->options.box_tracker,
      "on: boxes persist through missed detections and one-detection boxes are dropped (Detector.tracker)");
  cmd->add_option(
      "--geometry", args->options.geometry,
      "on (default): keypoints and map points that move against the estimated camera motion are kept "
      "out of tracking and mapping, with or without the people filter; off: the check is skipped "
      "(Geometry.dynamic_check)");
  cmd->add_option("--ground", args->options.ground,
                  "on: a monocular camera at a constant height above the ground (a car's); the run ends with a "
                  "global BA that holds each keyframe's ground at one height, against scale drift; off: not "
                  "(Ground.enabled; config/KITTI*.yaml turn it on)");
  cmd->add_option("--save-frames", args->options.save_frames,
                  "Write every N-th frame with boxes and kept/removed keypoints to OUT/frames/")
      ->check(count());
  cmd->add_flag(
      "--score-filter", args->options.score_filter,
      "Count the people filter's kept and removed keypoints on the person masks of DATASET/people_mask "
      "(written by crowdslam synth) into run.json people_masks");
  cmd->add_option(
      "--vocabulary", args->options.vocabulary,
      "ORB vocabulary for relocalisation (default: $CROWDSLAM_VOCABULARY or vocabulary/crowdslam_orb.voc); "
      "'none' relocalises by brute-force matching");
  cmd->add_flag("!--no-loop-closing", args->options.loop_closing,
                "Run without the loop closing thread (no place recognition, no pose-graph or global BA)");
  cmd->add_option(
         "--pace", args->pace,
         "none: every frame as fast as possible (default); sensor: replay at the recorded rate, dropping "
         "(and counting) frames that arrive while tracking is busy, as a live camera does")
      ->check(CLI::IsMember({"none", "sensor"}));
  cmd->add_flag("--skip-bad-frames", args->options.skip_bad_frames,
                "Skip (count and warn about) frames that cannot be read instead of failing the run");
  cmd->add_flag("--allow-untracked", args->options.allow_untracked,
                "Exit 0 even when no frame could be tracked");
  auto* save_map = cmd->add_option(
      "--save-map", args->options.save_map,
      "Write the final map to this SQLite file (atomically; also for an interrupted run). An existing file is "
      "replaced only when it is a crowdslam map and --overwrite is given");
  cmd->add_option(
      "--load-map", args->options.load_map,
      "Start in this saved map: relocalise into it, then extend it (or only track with --localization)");
  cmd->add_flag(
      "--viewer", args->options.viewer,
      "Live web viewer during the run (map, keyframes, camera, image with people, status, pause/step)");
  cmd->add_option("--viewer-host", args->options.viewer_host,
                  "Address the viewer listens on (default 127.0.0.1; the viewer has no authentication)");
  cmd->add_option("--viewer-port", args->options.viewer_port, "Viewer port (default 8080; 0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--viewer-pause-timeout", args->options.viewer_pause_timeout_s,
                  "Seconds a run paused from the viewer stays paused with no viewer page connected before it "
                  "resumes by itself (default 60; 0: stays paused until resumed or interrupted)")
      ->check(CLI::Range(0.0, 86400.0));
  cmd->add_flag("--localization", args->options.localization,
                "With --load-map: localisation only, no keyframe or map point is created or removed");
  // A path or name given as "" is a mistake, never "use the default".
  for (const char* name : {"--dataset", "--settings", "--out", "--detections", "--detector", "--vocabulary",
                           "--load-map", "--save-map", "--viewer-host", "--sensor"}) {
    cmd->get_option(name)->check(non_empty());
  }
  cmd->callback([args, save_map, &global] {
    args->options.save_map_given = save_map->count() > 0;
    if (!args->sensor.empty()) args->options.sensor = io::parse_sensor_kind(args->sensor, "--sensor");
    args->options.max_frames = args->frames;
    args->options.pace_sensor = args->pace == "sensor";
    args->options.progress = !global.quiet;
    InterruptScope interrupts;  // Ctrl-C / SIGTERM / SIGHUP stop the run and write its outputs
    const auto summary = run::run_sequence(args->options);
    if (global.json) {
      auto doc = summary.json;
      doc.erase("frames");
      print_json(doc);
    } else {
      print_summary(summary);
    }
    if (summary.end.kind == system::EndState::Kind::kInterrupted) global.exit_code = 128 + summary.end.signal;
  });
}

}  // namespace crowdslam::app
