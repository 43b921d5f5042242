// Where a build finds what lives beside it: the source tree (vocabulary/, models/, people_sprites/) and the
// public data (../shared, or $CROWDSLAM_SHARED).
#pragma once

#include <filesystem>

namespace crowdslam::util {

// The source tree this build was configured from.
std::filesystem::path source_dir();
// $CROWDSLAM_SHARED when set and not empty, else the folder CMake was given (CROWDSLAM_SHARED_DIR,
// default ../shared beside the source tree).
std::filesystem::path shared_dir();

}  // namespace crowdslam::util
