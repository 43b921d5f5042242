#pragma once
// Descriptor searches that only loop closing needs: projections through a similarity transform (the pose
// of a keyframe as the loop would correct it) rather than through the keyframe's own pose.
#include <memory>
#include <vector>

#include "crowdslam/geometry/sim3.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"

namespace crowdslam::loop {

// Extends the matches between kf1 and kf2 (matches_12[i]: kf2's map point matched to keypoint i of kf1,
// null = none; kf1 keypoints with a map point only) by projecting each keyframe's map points into the
// other through cam1_from_cam2 and its inverse; a pair is kept only when both projections pick each
// other (window radius * scale of the predicted level, Hamming < 100). Returns the number of new matches.
int search_by_sim3(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                   std::vector<std::shared_ptr<map::MapPoint>>& matches_12, const geometry::Sim3& cam1_from_cam2,
                   double radius);

// Projects `points` into `keyframe` placed at `cam_from_world` (a Sim3: the corrected pose) and records
// the best match (Hamming < 50, level within [predicted - 1, predicted]) of each point in `matched`
// (one slot per keypoint; slots already set and points already in `matched` are skipped).
// Returns the number of new matches.
int search_by_projection(const map::KeyFrame& keyframe, const geometry::Sim3& cam_from_world,
                         const std::vector<std::shared_ptr<map::MapPoint>>& points,
                         std::vector<std::shared_ptr<map::MapPoint>>& matched, double radius);

// Loop fusion: projects the loop's `points` into `keyframe` placed at `cam_from_world`. A match to a free
// keypoint adds the observation; a match to a keypoint that already has a (good) map point is recorded in
// `replace[k]` (that point is to be replaced by points[k]; the caller does it under the map-update lock).
// `replace` is resized to points.size(). Returns the number of matches.
int fuse_by_projection(const std::shared_ptr<map::KeyFrame>& keyframe, const geometry::Sim3& cam_from_world,
                       const std::vector<std::shared_ptr<map::MapPoint>>& points, double radius,
                       std::vector<std::shared_ptr<map::MapPoint>>& replace);

}  // namespace crowdslam::loop
