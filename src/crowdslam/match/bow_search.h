#pragma once
// Descriptor matching guided by the vocabulary's direct index (ORB-SLAM's SearchByBoW, our own code):
// only features that descend through the same vocabulary node (bow::FeatureVector) are compared, which
// needs no pose guess. Used by relocalisation, by tracking of the reference keyframe and by loop closing.
#include <memory>
#include <vector>

#include "crowdslam/map/frame.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"

namespace crowdslam::match {

// Matches the keyframe's keypoints that have a good map point to the frame's keypoints in the same
// direct-index node: best Hamming distance below kThLow and below nn_ratio x the second best; a frame
// keypoint goes to the closest keyframe keypoint. With check_orientation, the rotation histogram rejects
// inconsistent matches. `matches` is resized to frame.size(): matches[i] = map point matched to frame
// keypoint i, or null. Returns the number of matches (0 when either has no bag of words).
int search_by_bow(const map::KeyFrame& keyframe, const map::Frame& frame,
                  std::vector<std::shared_ptr<map::MapPoint>>& matches, double nn_ratio = 0.7,
                  bool check_orientation = true);

// Between two keyframes (loop closing): matches_12 is resized to kf1's keypoints; matches_12[i] = map
// point of kf2 matched to keypoint i of kf1, or null. Both keypoints must have good map points; each kf2
// keypoint is used at most once (by the kf1 keypoint closest to it). Same tests as above.
int search_by_bow(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                  std::vector<std::shared_ptr<map::MapPoint>>& matches_12, double nn_ratio = 0.75,
                  bool check_orientation = true);

}  // namespace crowdslam::match
