#pragma once
// Subcommands of the `crowdslam` tool. Each adds itself to the app; its callback does the work and
// throws crowdslam::InputError on bad input (main turns that into one line on stderr and exit 1).
// Exit codes: 0 success; 1 bad input or a failed run; 2 an internal error; 128 + signal for a run or synth
// stopped by SIGHUP (129), SIGINT (130) or SIGTERM (143). Logs go to stderr; stdout carries results only
// (with --json exactly one JSON document, also on errors: {"error": ..., "exit_code": ...}).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

namespace crowdslam::app {

struct GlobalOptions {
  bool json = false;     // machine-readable output on stdout
  bool quiet = false;    // warnings and errors only
  bool verbose = false;  // debug logging
  int exit_code = 0;     // set by a command that finished but must not exit 0 (an interrupted run: 128 + signal)
};

void add_dataset_command(CLI::App& app, const GlobalOptions& global);
void add_eval_command(CLI::App& app, const GlobalOptions& global);
void add_synth_command(CLI::App& app, GlobalOptions& global);
void add_synth_sprites_command(CLI::App& app, const GlobalOptions& global);
void add_run_command(CLI::App& app, GlobalOptions& global);
void add_detect_command(CLI::App& app, const GlobalOptions& global);
void add_vocab_command(CLI::App& app, const GlobalOptions& global);
void add_map_command(CLI::App& app, const GlobalOptions& global);
void add_view_command(CLI::App& app, const GlobalOptions& global);
void add_report_command(CLI::App& app, const GlobalOptions& global);

// Prints a JSON document (pretty, newline-terminated) to stdout.
void print_json(const nlohmann::json& document);

}  // namespace crowdslam::app
