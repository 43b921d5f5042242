#pragma once
// The current image being tracked: its features (shared with a keyframe if it becomes one), the map points
// matched to them, and its estimated pose. Owned by the tracking thread only (no locks).
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"
#include "crowdslam/map/frame_features.h"
#include "crowdslam/map/scale_levels.h"

namespace crowdslam::map {

class KeyFrame;
class MapPoint;

// Where a map point falls in a frame, for the projection searches (computed, never stored on the point).
struct PointProjection {
  double u = 0;
  double v = 0;
  double right_u = -1;     // < 0 if the frame has no right coordinates
  double distance = 0;     // from the camera centre
  double view_cos = 0;     // cosine between viewing ray and the point's mean normal
  int predicted_level = 0;
};

class Frame {
 public:
  Frame(uint64_t id, double timestamp_s, std::shared_ptr<const geometry::PinholeCamera> camera,
        std::shared_ptr<const ScaleLevels> levels, std::shared_ptr<const FrameFeatures> features);

  uint64_t id;
  double timestamp_s;
  std::shared_ptr<const geometry::PinholeCamera> camera;
  std::shared_ptr<const ScaleLevels> levels;
  std::shared_ptr<const FrameFeatures> features;

  std::vector<std::shared_ptr<MapPoint>> map_points;  // one slot per keypoint (null = unmatched)
  std::vector<bool> outliers;                          // set by pose optimisation
  // Geometric dynamic check (tracking/dynamic_check.h): keypoints judged to be on something that moves
  // (kept out of pose optimisation and of new map points), and per keypoint the moving/static verdicts of
  // its last three checked observations (bits 0-2, newest in bit 0) and how many there were (bits 4-5).
  std::vector<bool> dynamic;
  std::vector<uint8_t> motion_history;
  // Keypoints inside person boxes that tracking took back because they match trusted static map points
  // (Tracker::track): they help the pose, but nothing new in the map is made of them.
  std::vector<bool> in_box;
  std::optional<geometry::SE3> cam_from_world;
  std::shared_ptr<KeyFrame> reference_keyframe;
  // RGB-D: the frame's raw depth image (CV_16UC1 at raw, distorted pixels; 0 = no depth) and the metres
  // one unit stands for, for the dynamic check's free-space test. Empty for monocular and stereo. Shared
  // with the caller's image (cv::Mat reference count), never written.
  cv::Mat depth_raw;
  double depth_metres_per_unit = 0;

  [[nodiscard]] size_t size() const { return features->size(); }
  [[nodiscard]] geometry::Vec3 camera_center() const { return cam_from_world->inverse().translation(); }

  // Projection of a map point if it is in front of the camera, inside the image, within the point's
  // scale-invariance distance range, and seen at a viewing angle with cos >= min_view_cos (ORB-SLAM's
  // isInFrustum). Requires cam_from_world.
  [[nodiscard]] std::optional<PointProjection> project(const MapPoint& point, double min_view_cos = 0.5) const;

  // Number of matched, non-outlier map points that are not bad.
  [[nodiscard]] int num_tracked() const;
  // Clears outlier matches (sets their slots to null) and returns the number of remaining matches.
  int discard_outliers();
};

}  // namespace crowdslam::map
