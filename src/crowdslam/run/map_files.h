#pragma once
// The run's saved maps: checking --load-map / --save-map / --localization before anything runs,
// loading the map into the system, saving it at the end, and what run.json says about them
// (including, for a run in a loaded map, how soon and how often it localised).
#include <nlohmann/json.hpp>

#include <vector>

#include "crowdslam/run/run_sequence.h"
#include "crowdslam/system/system.h"

namespace crowdslam::run {

// Throws InputError for option combinations that cannot work (--localization without --load-map,
// --save-map with --localization, a --save-map directory that does not exist, a --save-map path that is
// empty, a special file, a file that is not a crowdslam map, or a map without --overwrite).
void check_map_options(const RunOptions& options);

// Loads options.load_map into `slam` when given; returns the run.json "map" object so far (null if no
// map option is used).
nlohmann::json load_map_if_requested(const RunOptions& options, system::System& slam);

// Frames localised, relocalisations and the time to the first localisation, into `map_json`.
void add_localization_stats(const std::vector<system::FrameReport>& reports, nlohmann::json& map_json);

// Saves the map when options.save_map is set; records the file, its size and the time in `map_json`.
// Throws InputError when the save fails (the old file, if any, is untouched).
void save_map_if_requested(const RunOptions& options, const system::System& slam, const std::string& end_state,
                           nlohmann::json& map_json);

}  // namespace crowdslam::run
