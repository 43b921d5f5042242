// crowdslam: visual SLAM that keeps working in crowds. Command-line entry point.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <exception>
#include <filesystem>
#include <iostream>
#include <new>

#include "commands.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/interrupt.h"
#include "crowdslam/util/text.h"
#include "crowdslam/util/version.h"

namespace crowdslam::app {
namespace {
bool g_json_printed = false;
}
void print_json(const nlohmann::json& document) {
  // Text from a hostile file (a map's blob in an error message) may be invalid UTF-8: replaced, never a throw.
  std::cout << document.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  g_json_printed = true;
}
}  // namespace crowdslam::app

namespace {
// One line on stderr; with --json also one JSON document on stdout, unless the command printed its own.
int fail(const crowdslam::app::GlobalOptions& global, std::string message, int code) {
  // One line, whatever the message holds (an SQLite report, a multi-line parse error).
  for (char& c : message) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  std::cerr << "error: " << message << '\n';
  if (global.json && !crowdslam::app::g_json_printed) {
    crowdslam::app::print_json({{"error", message}, {"exit_code", code}});
  }
  return code;
}

// A filesystem error names its paths; they can be huge (a 2 MB name): clipped.
std::string filesystem_message(const std::filesystem::filesystem_error& e) {
  std::string message;
  if (!e.path1().empty()) message += crowdslam::clip_text(e.path1().string(), 200) + ": ";
  if (!e.path2().empty()) message += crowdslam::clip_text(e.path2().string(), 200) + ": ";
  return message + e.code().message();
}
}  // namespace

int main(int argc, char** argv) {
  using namespace crowdslam::app;
  // Logs and progress on stderr, so stdout holds only results (and --json exactly one document).
  spdlog::set_default_logger(spdlog::stderr_color_mt("crowdslam"));
  crowdslam::install_cleanup_handlers();  // a signal never leaves a temporary file behind
  CLI::App app{"crowdslam: visual SLAM that keeps working in crowds"};
  app.set_version_flag("--version", crowdslam::version_line());
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
  add_synth_sprites_command(app, global);
  add_run_command(app, global);
  add_detect_command(app, global);
  add_vocab_command(app, global);
  add_map_command(app, global);
  add_view_command(app, global);
  add_report_command(app, global);

  // --json is known before parsing, so that a parse error is a JSON document too.
  for (int i = 1; i < argc && std::string(argv[i]) != "--"; ++i) {
    if (std::string(argv[i]) == "--json") global.json = true;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Bad arguments are bad input: exit 1 with one line (and --json's document), not CLI11's own codes.
    if (e.get_exit_code() == 0) return app.exit(e);
    return fail(global, crowdslam::clip_text(e.what(), 1000) + " (see --help)", 1);
  } catch (const crowdslam::Interrupted& e) {
    return fail(global, e.what(), e.exit_code());
  } catch (const crowdslam::InputError& e) {
    return fail(global, e.what(), 1);
  } catch (const std::filesystem::filesystem_error& e) {
    return fail(global, filesystem_message(e), 1);
  } catch (const std::bad_alloc&) {
    return fail(global, "out of memory", 2);
  } catch (const std::exception& e) {
    return fail(global, crowdslam::clip_text(e.what(), 1000), 2);
  }
  spdlog::default_logger()->flush();
  return global.exit_code;
}
