#pragma once
// The release version (CMake's project version, see CHANGELOG.md) and the git commit that was built.
// `crowdslam --version` prints both; run.json and saved maps record them.
#include <string>

namespace crowdslam {

// "0.10.0"
const char* version();
// The built checkout's commit, 12 hex digits, with "-dirty" when tracked files had changes; "unknown"
// when the sources were not a git checkout. Taken at build time (target crowdslam_git_commit).
const char* git_commit();
// "crowdslam 0.10.0 (git 0123456789ab)"
std::string version_line();

}  // namespace crowdslam
