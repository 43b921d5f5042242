#pragma once
// Descriptor matching searches used by tracking, local mapping and (later) loop closing.
// All searches are free functions over map types; none of them keeps state.
#include <memory>
#include <set>
#include <vector>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/map/frame.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"

namespace crowdslam::match {

inline constexpr int kThHigh = 100;  // max Hamming distance for projection searches
inline constexpr int kThLow = 50;    // max Hamming distance for triangulation / initialisation

// Best and second best distance among candidate keypoints for one descriptor.
struct BestMatch {
  int index = -1;
  int distance = 256;
  int level = -1;
  int second_distance = 256;
  int second_level = -1;
};

// A map point with its projection into the frame being tracked (see map::Frame::project).
struct ProjectedPoint {
  std::shared_ptr<map::MapPoint> point;
  map::PointProjection projection;
};

// Tracking the local map: matches each projected point (the caller has projected them and counted them
// as visible) to the best keypoint without a map point within a radius that grows with the predicted
// scale level (ratio test `nn_ratio` between best and second best when both are on the same level).
// `radius_factor` scales the window (1 normally, larger right after relocalisation). Returns the number
// of new matches written into frame.map_points.
int search_local_points(map::Frame& frame, const std::vector<ProjectedPoint>& projected, double radius_factor = 1.0,
                        double nn_ratio = 0.8);

// Motion model: projects the map points of `last` into `current` (which has a pose guess) and matches
// them in a window of radius * scale(level), restricting levels by the direction of motion for
// stereo/RGB-D, with the rotation-consistency check. Returns the number of matches.
int search_from_last_frame(map::Frame& current, const map::Frame& last, double radius, bool check_orientation = true);

// Matches keypoints of `keyframe` that have map points to keypoints of `frame` near the same pixel
// (window of `radius` px, any level within +-2 of the keyframe keypoint's), without a pose guess:
// the fallback "track reference keyframe" search before place recognition exists, and the frame-to-frame
// grid search. Ratio test nn_ratio, rotation check. Returns the number of matches written into frame.
int search_keyframe_window(map::Frame& frame, const map::KeyFrame& keyframe, double radius, double nn_ratio = 0.7,
                           bool check_orientation = true);

// Pairs (index in kf1, index in kf2) of keypoints without map points that satisfy the epipolar
// constraint (distance to the epipolar line below 3.84 sigma^2 at kf2's level) and match by descriptor
// (< kThLow, ratio 0.6... as ORB-SLAM: best only), with the rotation check. Used to triangulate new points.
// `fundamental_21` maps kf1 pixels to lines in kf2 (l2 = F21 * x1).
// When both keyframes carry a direct index (bag of words), only keypoints under the same vocabulary node
// are compared (ORB-SLAM2's SearchForTriangulation); without, every free pair.
std::vector<std::pair<size_t, size_t>> search_for_triangulation(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                                                                const geometry::Mat3& fundamental_21,
                                                                bool only_stereo = false,
                                                                bool check_orientation = true);

// Fundamental matrix between two keyframes: F21 with x2^T F21 x1 = 0 (pixels, undistorted).
geometry::Mat3 fundamental_between(const map::KeyFrame& kf1, const map::KeyFrame& kf2);

// Projects `points` into `keyframe` and fuses: a match to a keypoint that already has a map point merges
// the two (the one with fewer observations is replaced by the other); a match to a free keypoint adds an
// observation. `radius` as in search_local_points. Returns the number of fused points.
int fuse(const std::shared_ptr<map::KeyFrame>& keyframe, const std::vector<std::shared_ptr<map::MapPoint>>& points,
         double radius = 3.0);

}  // namespace crowdslam::match
