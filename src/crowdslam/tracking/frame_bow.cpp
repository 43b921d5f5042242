#include "crowdslam/tracking/frame_bow.h"

#include <memory>

namespace crowdslam::tracking {

void ensure_bow(map::Frame& frame, const bow::Vocabulary& vocabulary) {
  if (frame.features->has_bow() || frame.features->descriptors.empty() || vocabulary.empty()) return;
  auto features = std::make_shared<map::FrameFeatures>(*frame.features);
  vocabulary.transform(features->descriptors, features->bow, features->bow_features);
  frame.features = std::move(features);
}

}  // namespace crowdslam::tracking
