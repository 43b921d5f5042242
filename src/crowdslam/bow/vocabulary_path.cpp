#include "crowdslam/bow/vocabulary_path.h"

#include <cstdlib>
#include <filesystem>

#ifndef CROWDSLAM_SOURCE_DIR
#define CROWDSLAM_SOURCE_DIR "."
#endif

namespace crowdslam::bow {

std::string default_vocabulary_path() {
  if (const char* value = std::getenv("CROWDSLAM_VOCABULARY"); value != nullptr && *value != '\0')
    return value;
  return (std::filesystem::path(CROWDSLAM_SOURCE_DIR) / "vocabulary" / "crowdslam_orb.voc").string();
}

}  // namespace crowdslam::bow
