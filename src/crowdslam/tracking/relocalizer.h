#pragma once
// Relocalisation after tracking is lost: the frame is matched by descriptor against candidate keyframes'
// map points, a pose is found by PnP with RANSAC and refined by motion-only optimisation; more matches
// then come from projecting the candidate's covisible map points. Until the bag-of-words vocabulary
// exists, candidates are chosen by recency and covisibility and matching is brute force (a few ms per
// candidate), which is affordable because it only runs while lost.
#include <memory>
#include <vector>

#include "crowdslam/map/frame.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/optim/pose_optimizer.h"

namespace crowdslam::tracking {

struct RelocalizerOptions {
  int min_matches = 15;          // descriptor matches needed to try PnP with a candidate
  int min_pnp_inliers = 12;
  int min_final_inliers = 50;    // inliers after optimisation and projection search
  double ratio = 0.75;           // nearest / second nearest Hamming distance
  int max_distance = 64;         // Hamming
  int ransac_iterations = 200;
  double ransac_reprojection_px = 4.0;
};

class Relocalizer {
 public:
  explicit Relocalizer(const RelocalizerOptions& options = {}) : options_(options) {}

  // On success sets frame.cam_from_world and frame.map_points (inliers) and returns the keyframe it
  // relocalised against; nullptr when no candidate worked.
  std::shared_ptr<map::KeyFrame> relocalize(map::Frame& frame,
                                            const std::vector<std::shared_ptr<map::KeyFrame>>& candidates,
                                            const optim::PoseOptimizerOptions& pose_options) const;

 private:
  bool try_candidate(map::Frame& frame, const map::KeyFrame& candidate,
                     const optim::PoseOptimizerOptions& pose_options) const;
  RelocalizerOptions options_;
};

}  // namespace crowdslam::tracking
