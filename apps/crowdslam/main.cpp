// crowdslam: visual SLAM that keeps working in crowds. Command-line entry point.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.h"
#include "crowdslam/util/error.h"

namespace crowdslam::app {
void print_json(const nlohmann::json& document) { std::cout << document.dump(2) << '\n'; }
}  // namespace crowdslam::app

int main(int argc, char** argv) {
  using namespace crowdslam::app;
  CLI::App app{"crowdslam: visual SLAM that keeps working in crowds"};
  app.set_version_flag("--version", std::string("crowdslam ") + CROWDSLAM_VERSION);
  app.require_subcommand(1);
  GlobalOptions global;
  app.add_flag("--json", global.json, "Machine-readable JSON output on stdout");
  app.add_flag("-q,--quiet", global.quiet, "Only warnings and errors");
  app.add_flag("-v,--verbose", global.verbose, "Debug logging");
  app.parse_complete_callback([&global] {
    spdlog::set_pattern("[%l] %v");
    spdlog::set_level(global.quiet ? spdlog::level::warn
                                   : (global.verbose ? spdlog::level::debug : spdlog::level::info));
  });
  // Subcommands inherit --json/--quiet/--verbose so they may be given after the subcommand too.
  app.fallthrough();

  add_dataset_command(app, global);
  add_eval_command(app, global);
  add_synth_command(app, global);
  add_run_command(app, global);
  add_detect_command(app, global);
  add_vocab_command(app, global);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const crowdslam::InputError& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 2;
  }
  return 0;
}
