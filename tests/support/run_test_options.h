#pragma once
// The run options most end-to-end tests start from: `--sequential` (reproducible), no progress line, no
// people filter. Header-only, for tests that link crowdslam::run.
#include <filesystem>

#include "crowdslam/run/run_sequence.h"

namespace crowdslam::test {

inline run::RunOptions sequential_run_options(const std::filesystem::path& dataset,
                                              const std::filesystem::path& out) {
  run::RunOptions options;
  options.dataset = dataset.string();
  options.out_dir = out.string();
  options.sequential = true;
  options.progress = false;
  options.people_filter = false;
  return options;
}

}  // namespace crowdslam::test
