#include "crowdslam/util/version.h"

namespace crowdslam {

const char* version() { return CROWDSLAM_VERSION; }

std::string version_line() { return std::string("crowdslam ") + version() + " (git " + git_commit() + ")"; }

}  // namespace crowdslam
