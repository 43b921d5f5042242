#pragma once
// Subcommands of the `crowdslam` tool. Each adds itself to the app; its callback does the work and
// throws crowdslam::InputError on bad input (main turns that into one line on stderr and exit 1).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

namespace crowdslam::app {

struct GlobalOptions {
  bool json = false;     // machine-readable output on stdout
  bool quiet = false;    // warnings and errors only
  bool verbose = false;  // debug logging
};

void add_dataset_command(CLI::App& app, const GlobalOptions& global);
void add_eval_command(CLI::App& app, const GlobalOptions& global);
void add_synth_command(CLI::App& app, const GlobalOptions& global);
void add_run_command(CLI::App& app, const GlobalOptions& global);
void add_detect_command(CLI::App& app, const GlobalOptions& global);
void add_vocab_command(CLI::App& app, const GlobalOptions& global);

// Prints a JSON document (pretty, newline-terminated) to stdout.
void print_json(const nlohmann::json& document);

}  // namespace crowdslam::app
