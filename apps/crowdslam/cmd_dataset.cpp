#include "commands.h"

namespace crowdslam::app {

void add_dataset_command(CLI::App& app, const GlobalOptions& global) {
  (void)global;
  app.add_subcommand("dataset", "(not implemented yet)");
}

}  // namespace crowdslam::app
