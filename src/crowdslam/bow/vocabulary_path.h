#pragma once
// Where the default ORB vocabulary lives: $CROWDSLAM_VOCABULARY when set (and not empty), else
// <repo>/vocabulary/crowdslam_orb.voc (built by scripts/build_vocabulary.sh; the repository path is
// fixed at compile time). The file is not checked here; Vocabulary::read() reports a missing one.
#include <string>

namespace crowdslam::bow {

std::string default_vocabulary_path();

}  // namespace crowdslam::bow
