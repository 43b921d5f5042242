// `crowdslam map info|export|optimise`: look into a saved map, export it for other tools, refine it.
#include <filesystem>
#include <iostream>

#include "commands.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/map_export.h"
#include "crowdslam/mapdb/map_target.h"
#include "crowdslam/system/map_optimise.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::app {

namespace {
nlohmann::json stats_json(const system::ReprojectionStats& s) {
  return {{"observations", s.observations}, {"rms_px", s.rms_px}, {"median_px", s.median_px}, {"above_chi2", s.above_chi2}};
}

nlohmann::json info_json(const std::string& file, const mapdb::MapInfo& info) {
  const auto& id = info.header.identity;
  const auto& o = info.header.origin;
  return {{"file", file},
          {"file_bytes", info.file_bytes},
          {"schema_version", info.header.schema_version},
          {"sensor", id.sensor},
          {"camera",
           {{"fx", id.camera.fx}, {"fy", id.camera.fy}, {"cx", id.camera.cx}, {"cy", id.camera.cy},
            {"width", id.camera.width}, {"height", id.camera.height}, {"bf", id.camera.bf}}},
          {"depth_map_factor", id.depth_map_factor},
          {"orb", {{"features", id.orb_features}, {"scale_factor", id.orb_scale_factor}, {"levels", id.orb_levels}}},
          {"vocabulary", {{"hash", id.vocabulary_hash}, {"words", id.vocabulary_words}}},
          {"origin",
           {{"dataset", o.dataset}, {"created_utc", o.created_utc}, {"crowdslam_version", o.crowdslam_version},
            {"end_state", o.end_state}}},
          {"keyframes", info.keyframes},
          {"map_points", info.map_points},
          {"observations", info.observations},
          {"covisibility_edges", info.covisibility_edges},
          {"loop_edges", info.loop_edges},
          {"bounds",
           {{"min", {info.points_min[0], info.points_min[1], info.points_min[2]}},
            {"max", {info.points_max[0], info.points_max[1], info.points_max[2]}}}}};
}
}  // namespace

void add_map_command(CLI::App& app, const GlobalOptions& global) {
  auto* map_cmd = app.add_subcommand("map", "Inspect and export saved maps (run --save-map FILE.db)");
  map_cmd->require_subcommand(1);

  auto file = std::make_shared<std::string>();
  auto masks = std::make_shared<std::string>();
  auto* info = map_cmd->add_subcommand("info", "Keyframes, points, observations, loops, bounds, sensor, vocabulary");
  info->add_option("file", *file, "Map database")->required();
  info->add_option("--masks", *masks,
                   "Also count the map points observed on moving pixels: a folder of per-frame masks "
                   "(NNNNNN.png by frame index, non-zero = moving), e.g. the mask/ of crowdslam synth --movers");
  info->callback([file, masks, &global] {
    const auto map_info = mapdb::read_map_info(*file);
    auto doc = info_json(*file, map_info);
    if (!masks->empty()) {
      const auto m = mapdb::count_points_on_masks(*file, *masks);
      doc["masks"] = {{"mask_dir", *masks},
                      {"keyframes_with_mask", m.keyframes_with_mask},
                      {"points_checked", m.points_checked},
                      {"points_on_mask", m.points_on_mask},
                      {"fraction_on_mask", m.fraction()}};
    }
    if (global.json) {
      print_json(doc);
      return;
    }
    const auto& b = doc["bounds"];
    std::cout << "map               " << *file << " (" << map_info.file_bytes / 1024 << " KiB, schema "
              << map_info.header.schema_version << ")\n"
              << "sensor            " << map_info.header.identity.sensor << ", camera "
              << map_info.header.identity.camera.width << "x" << map_info.header.identity.camera.height << " fx "
              << map_info.header.identity.camera.fx << "\n"
              << "vocabulary        " << map_info.header.identity.vocabulary_hash << " ("
              << map_info.header.identity.vocabulary_words << " words)\n"
              << "origin            " << map_info.header.origin.dataset << ", " << map_info.header.origin.created_utc
              << ", crowdslam " << map_info.header.origin.crowdslam_version << ", run "
              << map_info.header.origin.end_state << "\n"
              << "keyframes         " << map_info.keyframes << "\n"
              << "map points        " << map_info.map_points << " (" << map_info.observations << " observations)\n"
              << "covisibility      " << map_info.covisibility_edges << " edges\n"
              << "loop edges        " << map_info.loop_edges << "\n"
              << "bounds            " << b["min"].dump() << " to " << b["max"].dump() << "\n";
    if (doc.contains("masks")) {
      const auto& m = doc["masks"];
      std::cout << "on masks          " << m["points_on_mask"] << " of " << m["points_checked"]
                << " points seen by the " << m["keyframes_with_mask"] << " keyframes with a mask ("
                << 100.0 * m["fraction_on_mask"].get<double>() << " %)\n";
    }
  });

  struct ExportArgs {
    std::string file, ply, keyframes, trajectory;
  };
  auto args = std::make_shared<ExportArgs>();
  auto* exp = map_cmd->add_subcommand("export", "Points as binary PLY, keyframes as PLY, keyframe trajectory (TUM)");
  exp->add_option("file", args->file, "Map database")->required();
  exp->add_option("--ply", args->ply, "Map points (x y z float, observations uint) as binary PLY");
  exp->add_option("--keyframes", args->keyframes, "Keyframe positions as binary PLY");
  exp->add_option("--trajectory", args->trajectory, "Keyframe trajectory, TUM format");
  exp->callback([args, &global] {
    if (args->ply.empty() && args->keyframes.empty() && args->trajectory.empty()) {
      throw InputError("map export: give at least one of --ply, --keyframes, --trajectory");
    }
    // Never over the map itself, another map, a special file, or each other.
    mapdb::read_map_header(args->file);  // the input is a map (a clear error first)
    const std::vector<std::pair<const char*, std::string*>> outputs = {
        {"--ply", &args->ply}, {"--keyframes", &args->keyframes}, {"--trajectory", &args->trajectory}};
    for (size_t i = 0; i < outputs.size(); ++i) {
      if (outputs[i].second->empty()) continue;
      mapdb::check_export_target(*outputs[i].second, args->file, outputs[i].first);
      for (size_t j = 0; j < i; ++j) {
        std::error_code ec;
        const auto a = std::filesystem::weakly_canonical(*outputs[i].second, ec);
        const auto b = std::filesystem::weakly_canonical(*outputs[j].second, ec);
        if (!outputs[j].second->empty() && !ec && a == b) {
          throw InputError(std::string(outputs[i].first) + " and " + outputs[j].first + ": the same file (" +
                           clip_text(*outputs[i].second) + "); give each export its own path");
        }
      }
    }
    nlohmann::json doc = {{"file", args->file}};
    if (!args->ply.empty()) doc["points"] = mapdb::export_points_ply(args->file, args->ply);
    if (!args->keyframes.empty()) doc["keyframes"] = mapdb::export_keyframes_ply(args->file, args->keyframes);
    if (!args->trajectory.empty()) doc["trajectory_poses"] = mapdb::export_keyframe_trajectory(args->file, args->trajectory);
    if (global.json) {
      print_json(doc);
    } else {
      if (doc.contains("points")) std::cout << "points            " << doc["points"] << " -> " << args->ply << "\n";
      if (doc.contains("keyframes")) std::cout << "keyframes         " << doc["keyframes"] << " -> " << args->keyframes << "\n";
      if (doc.contains("trajectory_poses")) {
        std::cout << "trajectory        " << doc["trajectory_poses"] << " poses -> " << args->trajectory << "\n";
      }
    }
  });

  struct OptimiseArgs {
    std::string input, output;
    system::MapOptimiseOptions options;
  };
  auto opt = std::make_shared<OptimiseArgs>();
  auto* optimise = map_cmd->add_subcommand(
      "optimise", "Global bundle adjustment of a saved map (every keyframe and point), written to a new map file");
  optimise->add_option("file", opt->input, "Map database")->required();
  optimise->add_option("--out", opt->output, "Map database to write (atomically)")->required();
  optimise->add_option("--iterations", opt->options.iterations, "Levenberg-Marquardt iterations")
      ->capture_default_str();
  optimise->add_flag("--overwrite", opt->options.overwrite, "Replace an existing output file (it may be the input)");
  optimise->add_option("--ground", opt->options.ground_sigma,
                       "A monocular map of a camera at a constant height above the ground (a car's): also hold "
                       "each keyframe's ground at one height, with this relative sigma per keyframe (as "
                       "Ground.keyframe_sigma, e.g. 0.01; 0 = off)");
  optimise->callback([opt, &global] {
    // Only a new file or (--overwrite) a crowdslam map is replaced, checked before the work.
    mapdb::check_map_target(opt->output, opt->options.overwrite, "--out");
    const auto r = system::optimise_saved_map(opt->input, opt->output, opt->options);
    const nlohmann::json doc = {{"file", opt->input},       {"out", opt->output},
                                {"keyframes", r.keyframes}, {"map_points", r.map_points},
                                {"iterations", r.iterations}, {"initial_cost", r.initial_cost},
                                {"final_cost", r.final_cost}, {"before", stats_json(r.before)},
                                {"after", stats_json(r.after)}, {"time_ms", r.time_ms},
                                {"keyframes_with_ground", r.keyframes_with_ground},
                                {"ground_points", r.ground_points}};
    if (global.json) {
      print_json(doc);
      return;
    }
    std::cout << "map               " << opt->input << ": " << r.keyframes << " keyframes, " << r.map_points
              << " points, " << r.before.observations << " observations\n"
              << "reprojection      rms " << r.before.rms_px << " px -> " << r.after.rms_px << " px, median "
              << r.before.median_px << " -> " << r.after.median_px << " px, above chi2 " << r.before.above_chi2
              << " -> " << r.after.above_chi2 << "\n"
              << "cost              " << r.initial_cost << " -> " << r.final_cost << " (" << r.iterations
              << " iterations, " << static_cast<int>(r.time_ms) << " ms)\n";
    if (opt->options.ground_sigma > 0) {
      std::cout << "ground            under " << r.keyframes_with_ground << " of " << r.keyframes << " keyframes ("
                << r.ground_points << " points)\n";
    }
    std::cout
              << "written           " << opt->output << "\n";
  });
}

}  // namespace crowdslam::app
