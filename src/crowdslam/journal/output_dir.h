#pragma once
// The run's output directory (--out), checked before any work and prepared before the first frame.
//
// Rules (README "Output files"):
//   - it may not exist yet (it is created, with its parents), or be an empty directory;
//   - a directory holding an earlier crowdslam run (its run.json) is refused unless `overwrite`; with
//     it, the earlier run's files are removed first, so the directory never mixes two runs;
//   - a directory holding anything crowdslam does not write is never touched (refused even with
//     `overwrite`), and neither is a file, a read-only location or a path that cannot be created.
// Errors are InputError naming the path (clipped) and the reason.
#include <filesystem>
#include <string>
#include <vector>

namespace crowdslam::journal {

// Names crowdslam writes into --out (files and the frames/ folder), and the temporaries of them.
[[nodiscard]] bool is_run_output_name(const std::string& name);

// No side effects: throws InputError when `out` cannot become the run's output directory.
void check_output_dir(const std::filesystem::path& out, bool overwrite);

// check_output_dir, then creates `out` or removes the earlier run's files; finally proves the directory
// writable by creating and removing a probe file. Returns the names it removed.
std::vector<std::string> prepare_output_dir(const std::filesystem::path& out, bool overwrite);

}  // namespace crowdslam::journal
