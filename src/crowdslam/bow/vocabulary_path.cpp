#include "crowdslam/bow/vocabulary_path.h"

#include <cstdlib>
#include <filesystem>

#include "crowdslam/util/project_paths.h"

namespace crowdslam::bow {

std::string default_vocabulary_path() {
  if (const char* value = std::getenv("CROWDSLAM_VOCABULARY"); value != nullptr && *value != '\0')
    return value;
  return (util::source_dir() / "vocabulary" / "crowdslam_orb.voc").string();
}

}  // namespace crowdslam::bow
