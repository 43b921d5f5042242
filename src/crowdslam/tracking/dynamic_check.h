#pragma once
// Geometric dynamic check (issue 16): after tracking has estimated a frame's pose against the static map,
// every keypoint matched to a map point or to a keypoint of the last frame (the visual-odometry points of
// RGB-D/stereo) is tested against that pose: its reprojection error and, with depth, its disparity error,
// weighed by the keypoint's pyramid level, as the pose optimisation's chi-square test (2 dof monocular,
// 3 dof with depth) but at a stricter threshold so that noise does not count as motion, and scaled by the
// frame's own median residual when that is larger than the levels predict (noisy depth).
//
// A single bad residual may be a wrong match; motion is what persists. Each keypoint carries the verdicts
// of its last three checked observations from frame to frame along its matches (Frame::motion_history),
// and each map point the verdicts of its last 8 checked observations (MapPoint::record_motion). A
// keypoint is dynamic when two of its last three observations moved (or, optionally, a single one by
// far), or when all of its map point's last 8 did (dynamic_score). Dynamic keypoints then grow into
// regions: unmatched keypoints next to a dynamic one in the image, at a similar depth when both have one,
// are dynamic too (up to two steps), so that a moving object's unmatched keypoints go with it.
//
// What dynamic means for the rest of tracking: no say in the pose (pose_refinement skips them), no new
// map points (Tracker::create_new_keyframe leaves them out of the keyframe), and a map point seen moving
// repeatedly (in all of its last 8 checked observations, cull_score) is culled from the map.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "crowdslam/map/frame.h"
#include "crowdslam/optim/pose_optimizer.h"

namespace crowdslam::tracking {

struct DynamicCheckOptions {
  bool enabled = true;
  // A residual counts as motion above factor x the pose optimisation's chi-square threshold (5.991 with
  // 2 dof, 7.815 with 3): chi2 > 4 x 7.815 (a 5.6 sigma error) is never noise. With 2 a synthetic crowd
  // seen through lagging boxes lost track for good at frame 54 (docs/RESULTS.md).
  double moving_factor = 4.0;
  // One observation alone makes a keypoint dynamic above this factor (0 = never: a wrong match can be
  // as far off as the search window, so by default motion must persist over two observations).
  double certain_factor = 0.0;
  int dynamic_score = 8;  // moving verdicts among a map point's last 8 that make its keypoints dynamic (and excluded)
  int cull_score = 8;     // moving verdicts among its last 8 at which the point is culled
  // Region growing, in pixels at 640 px image width (scaled with the width): radius around a dynamic
  // keypoint, and depth similarity (|dz| <= max(region_depth_m, region_depth_ratio * z)).
  double region_radius_px = 20.0;
  double region_depth_m = 0.15;
  double region_depth_ratio = 0.08;
  int region_steps = 2;
  // Static-first pose: when at least min_trusted matches are trusted (map points seen this often, counting
  // a depth observation twice, judged moving at most once in its last 8), the pose is first estimated from them alone and the
  // other matches that disagree with it are left out of the full optimisation (0 = off).
  int trusted_observations = 6;
  int min_trusted = 30;
  // Free-space test (RGB-D): a map point of the local map that projects into the frame but is not
  // matched, where the depth image sees a surface farther than the point by more than
  // max(free_space_margin_m, free_space_ratio * z) over the whole window around its projection, cannot
  // be there (the camera sees through it): a moving verdict for the point. A mover's points, once it has
  // moved on, are never matched again, so only this test gets them culled (0 = off).
  double free_space_margin_m = 0.2;
  double free_space_ratio = 0.1;
  // A point seen through this many times in a row (no matched observation in between) is culled: it has
  // moved, or it never was where the map has it.
  int free_space_cull_run = 2;
  void check() const;
};

struct DynamicCheckStats {
  int checked = 0;         // matches tested against the pose
  int moving = 0;          // of those, judged moving in this frame
  int dynamic = 0;         // keypoints dynamic after the check (region growth included)
  int grown = 0;           // of those, added by region growing
  int points_culled = 0;   // map points culled as moving (by the verdicts and the free-space test)
  int free_space = 0;      // unmatched local map points the depth image sees through (free_space())
  bool skipped = false;    // the frame failed with the check and was tracked without it (Tracker::track)
};

class DynamicCheck {
 public:
  explicit DynamicCheck(const DynamicCheckOptions& options);

  [[nodiscard]] bool enabled() const { return options_.enabled && !suspended_; }
  // While suspended the check does nothing (Tracker::track's retry of a frame that failed with it).
  void set_suspended(bool suspended) { suspended_ = suspended; }

  // Before a pose optimisation: marks as dynamic the frame's matches that are known to move (their map
  // point's score, or the last frame's keypoint they were matched through). `last` may be null.
  void inherit(map::Frame& frame, const map::Frame* last);

  // Before a pose optimisation, after inherit(): the static-first screening (options above). Sets
  // frame.cam_from_world to the trusted pose and marks the matches that disagree with it dynamic for the
  // optimisation (update() judges them afresh). Returns the number of matches screened out.
  int screen(map::Frame& frame, const optim::PoseOptimizerOptions& pose_options) const;
  // The frame's matches that are trusted (see screen) and inliers of its pose (not outliers, not dynamic).
  [[nodiscard]] int trusted_inliers(const map::Frame& frame) const;

  // After the frame's pose is final: tests every match, updates the keypoints' histories and the map
  // points' scores, culls map points seen moving repeatedly, and grows regions. `last` may be null.
  DynamicCheckStats update(map::Frame& frame, const map::Frame* last);

  // After update(), RGB-D only (frame.depth_raw): the free-space test (options above) of the local map
  // points not matched in this frame; records their moving verdicts and culls as update() does.
  void free_space(const map::Frame& frame, const std::vector<std::shared_ptr<map::MapPoint>>& local_points,
                  DynamicCheckStats& stats) const;

 private:
  void grow_regions(map::Frame& frame, const std::vector<bool>& judged, DynamicCheckStats& stats) const;
  // Seen often enough (trusted_observations) and judged moving at most once in its last 8 checks.
  [[nodiscard]] bool trusted_point(const map::MapPoint& point) const;

  DynamicCheckOptions options_;
  bool suspended_ = false;
};

}  // namespace crowdslam::tracking
