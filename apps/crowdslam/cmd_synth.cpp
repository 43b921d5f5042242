#include "commands.h"

namespace crowdslam::app {

void add_synth_command(CLI::App& app, const GlobalOptions& global) {
  (void)global;
  app.add_subcommand("synth", "(not implemented yet)");
}

}  // namespace crowdslam::app
