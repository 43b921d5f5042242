#pragma once
// The viewer's messages (JSON text for the page, docs/VIEWER.md): frame status, the current image with its
// person boxes and keypoints, the map snapshot, the aligned ground truth.
#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

#include "crowdslam/geometry/umeyama.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/system/run_observer.h"
#include "crowdslam/system/system.h"

namespace crowdslam::viewer {

// What the status bar and the camera need from one frame (copied on the tracking thread).
struct FrameStatus {
  size_t index = 0;
  double timestamp_s = 0;
  std::string state;
  std::string method;
  std::optional<geometry::SE3> world_from_cam;
  double fps = 0;
  double tracking_ms = 0;
  int keypoints = 0;
  int tracked_points = 0;
  int person_boxes = 0;
  double people_area = 0;
  int feature_budget = 0;
  size_t keyframes = 0;
  bool paused = false;
};

std::string frame_json(const FrameStatus& status);
// The image (JPEG, base64) with the drawing data the page overlays: boxes, kept and removed keypoints.
std::string image_json(size_t index, const cv::Mat& image, const std::vector<people::PersonBox>& boxes,
                       const std::vector<cv::KeyPoint>& kept, const std::vector<cv::KeyPoint>& removed,
                       int max_width);
// Points (positions in mm, observation counts), keyframe poses, edges.
std::string map_json(const system::MapSnapshot& snapshot);
// Ground-truth positions mapped into the map frame by `alignment` (subsampled to at most `max_points`).
std::string ground_truth_json(const io::Trajectory& ground_truth, const geometry::Similarity& alignment,
                              size_t max_points);
// Trajectory positions (a finished run's, or a saved map's keyframes, for `crowdslam view`).
std::string trajectory_json(const io::Trajectory& trajectory);

// Alignment of the ground truth onto the estimated positions (matched by nearest stamp within 20 ms):
// nullopt with fewer than `min_pairs` matches. Sim3 when `with_scale` (monocular), else SE3.
std::optional<geometry::Similarity> align_ground_truth(const io::Trajectory& ground_truth,
                                                      const std::vector<std::pair<double, geometry::Vec3>>& estimate,
                                                      bool with_scale, size_t min_pairs = 10);

std::string base64(const std::vector<uint8_t>& bytes);

}  // namespace crowdslam::viewer
