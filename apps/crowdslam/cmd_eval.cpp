// `crowdslam eval ate|rpe GT EST`: trajectory accuracy exactly as TUM's evaluate_ate.py / evaluate_rpe.py.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "crowdslam/eval/ate.h"
#include "crowdslam/eval/rpe.h"
#include "crowdslam/eval/unique_stamps.h"
#include "crowdslam/io/trajectory.h"

namespace crowdslam::app {
namespace {

struct AteArgs {
  std::string ground_truth;
  std::string estimate;
  std::string alignment = "se3";
  eval::AteOptions options;
  std::string save_aligned;
};

struct RpeArgs {
  std::string ground_truth;
  std::string estimate;
  std::string delta_unit = "s";
  eval::RpeOptions options;
};

io::Trajectory read_logged(const std::string& path) {
  spdlog::debug("{}: {} trajectory", path, io::to_string(io::detect_trajectory_format(path)));
  return io::read_trajectory(path);
}

nlohmann::json stats_json(const eval::ErrorStats& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std},   {"min", s.min},   {"max", s.max}};
}

// One line per statistic, as the TUM scripts print with --verbose ("<prefix>.rmse 0.012345 m").
void print_stats(const std::string& prefix, const eval::ErrorStats& s, const char* unit) {
  const std::pair<const char*, double> rows[] = {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
                                                 {"std", s.std},   {"min", s.min},   {"max", s.max}};
  for (const auto& [name, value] : rows) std::printf("%s.%s %f %s\n", prefix.c_str(), name, value, unit);
}

void run_ate(const AteArgs& args, const GlobalOptions& global) {
  eval::AteOptions options = args.options;
  options.alignment = eval::parse_alignment(args.alignment);
  options.check();
  const io::Trajectory gt = read_logged(args.ground_truth);
  const io::Trajectory est = read_logged(args.estimate);
  const eval::AteResult r = eval::evaluate_ate(gt, est, options, args.ground_truth, args.estimate);
  if (!args.save_aligned.empty()) {
    const io::Trajectory aligned =
        eval::apply_alignment(eval::unique_sorted_by_stamp(est), r.alignment, options.scale);
    io::write_tum_trajectory(args.save_aligned, aligned);
  }
  const geometry::Similarity& a = r.alignment;
  if (global.json) {
    nlohmann::json rotation = nlohmann::json::array();
    for (int i = 0; i < 3; ++i) rotation.push_back({a.rotation(i, 0), a.rotation(i, 1), a.rotation(i, 2)});
    print_json({{"metric", "ate"},
                {"ground_truth", args.ground_truth},
                {"estimate", args.estimate},
                {"alignment", eval::to_string(options.alignment)},
                {"max_difference_s", options.max_difference_s},
                {"offset_s", options.offset_s},
                {"scale", options.scale},
                {"ground_truth_poses", r.ground_truth_poses},
                {"estimate_poses", r.estimate_poses},
                {"compared_pose_pairs", r.matches.size()},
                {"absolute_translational_error_m", stats_json(r.translation_error_m)},
                {"transform",
                 {{"rotation", rotation},
                  {"translation", {a.translation.x(), a.translation.y(), a.translation.z()}},
                  {"scale", a.scale}}}});
    return;
  }
  std::printf("compared_pose_pairs %zu pairs\n", r.matches.size());
  print_stats("absolute_translational_error", r.translation_error_m, "m");
  std::printf("alignment %s\n", eval::to_string(options.alignment));
  std::printf("alignment.scale %f\n", a.scale);
  std::printf("alignment.translation %f %f %f m\n", a.translation.x(), a.translation.y(), a.translation.z());
  std::fflush(stdout);
}

void run_rpe(const RpeArgs& args, const GlobalOptions& global) {
  eval::RpeOptions options = args.options;
  options.delta_unit = eval::parse_delta_unit(args.delta_unit);
  options.check();
  const io::Trajectory gt = read_logged(args.ground_truth);
  const io::Trajectory est = read_logged(args.estimate);
  const eval::RpeResult r = eval::evaluate_rpe(gt, est, options, args.ground_truth, args.estimate);
  if (global.json) {
    print_json({{"metric", "rpe"},
                {"ground_truth", args.ground_truth},
                {"estimate", args.estimate},
                {"delta", options.delta},
                {"delta_unit", eval::to_string(options.delta_unit)},
                {"offset_s", options.offset_s},
                {"scale", options.scale},
                {"ground_truth_max_time_difference_s", r.ground_truth_max_time_difference_s},
                {"compared_pose_pairs", r.pairs.size()},
                {"translational_error_m", stats_json(r.translation_error_m)},
                {"rotational_error_deg", stats_json(r.rotation_error_deg)}});
    return;
  }
  std::printf("compared_pose_pairs %zu pairs\n", r.pairs.size());
  print_stats("translational_error", r.translation_error_m, "m");
  print_stats("rotational_error", r.rotation_error_deg, "deg");
  std::fflush(stdout);
}

void add_ate_command(CLI::App& eval_app, const GlobalOptions& global) {
  auto args = std::make_shared<AteArgs>();
  CLI::App* ate = eval_app.add_subcommand("ate", "Absolute trajectory error (as TUM evaluate_ate.py)");
  ate->add_option("GT", args->ground_truth, "Ground-truth trajectory (TUM, KITTI or EuRoC)")->required();
  ate->add_option("EST", args->estimate, "Estimated trajectory (TUM, KITTI or EuRoC)")->required();
  ate->add_option("--align", args->alignment, "Alignment: se3, sim3 (monocular) or none")
      ->capture_default_str();
  ate->add_option("--max-diff", args->options.max_difference_s, "Max timestamp difference for matching (s)")
      ->capture_default_str();
  ate->add_option("--offset", args->options.offset_s, "Time offset added to the estimate's stamps (s)")
      ->capture_default_str();
  ate->add_option("--scale", args->options.scale, "Scale applied to the estimate's positions")
      ->capture_default_str();
  ate->add_option("--save-aligned", args->save_aligned, "Write the aligned estimate here (TUM format)");
  ate->callback([args, &global] { run_ate(*args, global); });
}

void add_rpe_command(CLI::App& eval_app, const GlobalOptions& global) {
  auto args = std::make_shared<RpeArgs>();
  CLI::App* rpe = eval_app.add_subcommand("rpe", "Relative pose error, fixed delta (as TUM evaluate_rpe.py)");
  rpe->add_option("GT", args->ground_truth, "Ground-truth trajectory (TUM, KITTI or EuRoC)")->required();
  rpe->add_option("EST", args->estimate, "Estimated trajectory (TUM, KITTI or EuRoC)")->required();
  rpe->add_option("--delta", args->options.delta, "Pose distance of the compared pairs")
      ->capture_default_str();
  rpe->add_option("--delta-unit", args->delta_unit, "Unit of --delta: s or frames")->capture_default_str();
  rpe->add_option("--offset", args->options.offset_s, "Time offset added to the estimate's stamps (s)")
      ->capture_default_str();
  rpe->add_option("--scale", args->options.scale, "Scale applied to the estimate's translations")
      ->capture_default_str();
  rpe->callback([args, &global] { run_rpe(*args, global); });
}

}  // namespace

void add_eval_command(CLI::App& app, const GlobalOptions& global) {
  CLI::App* eval_app =
      app.add_subcommand("eval", "Trajectory accuracy against ground truth (TUM benchmark metrics)");
  eval_app->require_subcommand(1);
  add_ate_command(*eval_app, global);
  add_rpe_command(*eval_app, global);
}

}  // namespace crowdslam::app
