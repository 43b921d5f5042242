#pragma once
// Bag of words computed on demand. Transforming a frame's descriptors costs about 0.6 ms (a tree descent
// per descriptor, mostly cache misses) and most frames never need it: only keyframes (keyframe database,
// loop closing), reference-keyframe tracking and relocalisation use it. So, as in ORB-SLAM2, tracking
// computes it when one of those needs it rather than for every frame.
#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/map/frame.h"

#include <memory>
#include <vector>

namespace crowdslam::tracking {

// Gives frame.features its bag of words and direct index if it has none yet: the features are shared and
// immutable, so the frame gets a copy that has them (the descriptor matrix is shared, not copied).
// No-op for a frame that has them or has no descriptors.
void ensure_bow(map::Frame& frame, const bow::Vocabulary& vocabulary);

// The features without the keypoints flagged in `drop` (the dynamic ones, for a keyframe that must not
// make map points of them): a new FrameFeatures with its own grid, and its bag of words when a vocabulary
// is given. new_index[i] is keypoint i's index in the result, -1 for a dropped one.
std::shared_ptr<map::FrameFeatures> features_without(const map::FrameFeatures& features, const std::vector<bool>& drop,
                                                     std::vector<long>& new_index, const bow::Vocabulary* vocabulary);

}  // namespace crowdslam::tracking
