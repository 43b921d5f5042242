#include "crowdslam/util/project_paths.h"

#include <cstdlib>

#ifndef CROWDSLAM_DEFAULT_SHARED
#define CROWDSLAM_DEFAULT_SHARED "../shared"
#endif
#ifndef CROWDSLAM_SOURCE_DIR
#define CROWDSLAM_SOURCE_DIR "."
#endif

namespace crowdslam::util {

std::filesystem::path source_dir() { return CROWDSLAM_SOURCE_DIR; }

std::filesystem::path shared_dir() {
  const char* shared = std::getenv("CROWDSLAM_SHARED");
  return (shared != nullptr && *shared != '\0') ? std::filesystem::path(shared)
                                                : std::filesystem::path(CROWDSLAM_DEFAULT_SHARED);
}

}  // namespace crowdslam::util
