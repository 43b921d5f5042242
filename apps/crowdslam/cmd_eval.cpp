#include "commands.h"

namespace crowdslam::app {

void add_eval_command(CLI::App& app, const GlobalOptions& global) {
  (void)global;
  app.add_subcommand("eval", "(not implemented yet)");
}

}  // namespace crowdslam::app
