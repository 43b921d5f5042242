#pragma once
// Relocalisation after tracking is lost: the frame is matched by descriptor against candidate keyframes'
// map points, a pose is found by PnP with RANSAC and refined by motion-only optimisation; more matches
// then come from projecting the candidate's covisible map points.
//
// With a bag of words on both the frame and a candidate, matching uses the vocabulary's direct index
// (match::search_by_bow) and the candidates are tried in decreasing number of matches; the caller picks
// the candidates with the keyframe database. Without a vocabulary, matching is brute force against each
// candidate's points in the order given (a few ms per candidate, affordable because it only runs while
// lost).
#include <memory>
#include <utility>
#include <vector>

#include "crowdslam/map/frame.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/optim/pose_optimizer.h"

namespace crowdslam::tracking {

struct RelocalizerOptions {
  int min_matches = 15;          // descriptor matches needed to try PnP with a candidate
  int min_pnp_inliers = 12;
  int min_optimized_inliers = 10;  // after the first pose optimisation
  int min_final_inliers = 50;    // inliers after optimisation and projection search
  // Between this and min_final_inliers after the wide projection search, a second, narrow one is tried
  // (ORB-SLAM2's two-stage search).
  int retry_min_inliers = 30;
  double ratio = 0.75;           // nearest / second nearest Hamming distance
  int max_distance = 64;         // Hamming, brute-force matching and the narrow projection search
  int ransac_iterations = 200;
  double ransac_reprojection_px = 4.0;
  double wide_radius_factor = 3.0;    // projection search windows (see match::search_local_points)
  double narrow_radius_factor = 1.0;
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
  using Matches = std::vector<std::pair<size_t, std::shared_ptr<map::MapPoint>>>;  // frame keypoint, point
  bool try_candidate(map::Frame& frame, const map::KeyFrame& candidate, const Matches& matches,
                     const optim::PoseOptimizerOptions& pose_options) const;
  // Matches from projecting the candidate's and its neighbours' points (new matches farther than
  // max_distance are dropped unless it is kNoDistanceLimit); returns how many were added.
  int search_by_projection(map::Frame& frame, const map::KeyFrame& candidate, double radius_factor,
                           int max_distance) const;
  static constexpr int kNoDistanceLimit = -1;
  RelocalizerOptions options_;
};

}  // namespace crowdslam::tracking
