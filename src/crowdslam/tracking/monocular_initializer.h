#pragma once
// Monocular initialisation (ORB-SLAM's method, our code): a reference frame is kept and each following
// frame is matched to it; when the two views give a valid two-view reconstruction
// (geometry/two_view.h), the initial map is built from them.
//
// Matching: each reference keypoint (levels <= max_level) is searched for in a square window around the
// position it was last matched at (starting at its own position), among current keypoints of the same
// level; best Hamming distance <= kThLow, ratio test, one match per current keypoint (the closer one
// wins), rotation-consistency check. Matched positions are carried over, so the window follows the
// motion.
// Reference policy: a frame with too few keypoints never becomes the reference; a current frame with too
// few keypoints or too few matches becomes the new reference (retry).
// Prior: when re-anchoring a map, a motion model predicts the relative pose of the two views
// (set_prior); the two-view step then keeps only hypotheses that agree with it (geometry/two_view.h,
// step 5), which resolves a plane's two-fold ambiguity and rejects reconstructions the motion rules out.
//
// build_initial_map() then creates two keyframes (the reference at the origin), the triangulated points,
// runs a bundle adjustment of the two with the first fixed, removes outlier observations, scales the map
// so that the first keyframe's median scene depth is 1, and checks that enough points survive.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "crowdslam/geometry/two_view.h"
#include "crowdslam/map/frame.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"

namespace crowdslam::tracking {

struct MonocularInitializerOptions {
  int min_keypoints = 100;   // a frame needs more keypoints than this to take part
  int min_matches = 100;     // fewer matches with the reference: the current frame becomes the reference
  double window_px = 100.0;  // search window half-size around the last matched position
  double nn_ratio = 0.9;
  int max_level = 0;         // reference keypoints used (pyramid levels 0..max_level)
  int min_map_points = 100;  // points the second keyframe must keep after bundle adjustment
  int ba_iterations = 20;
  geometry::TwoViewOptions two_view;
  void check() const;  // throws InputError naming the bad option
};

// A successful two-view reconstruction between the reference frame and the current frame.
struct TwoViewInitialization {
  std::shared_ptr<const map::Frame> reference;  // its map point slots are unused
  geometry::SE3 current_from_reference;         // unit baseline (scale fixed by build_initial_map)
  geometry::TwoViewModel model = geometry::TwoViewModel::kFundamental;
  double parallax_deg = 0.0;
  struct Match {
    size_t reference_index;
    size_t current_index;
    geometry::Vec3 point_reference;  // triangulated, in the reference camera
  };
  std::vector<Match> matches;  // triangulated matches only
  int num_matches = 0;         // all descriptor matches given to the two-view step
};

class MonocularInitializer {
 public:
  explicit MonocularInitializer(const MonocularInitializerOptions& options = {});

  // Offers a frame (undistorted keypoints, no pose needed). Returns the reconstruction when this frame
  // and the reference give one; otherwise keeps or replaces the reference and returns nullopt.
  std::optional<TwoViewInitialization> add_frame(const map::Frame& frame);
  // Gives the relative pose (reference frame -> current frame) predicted between two timestamps, or
  // nullopt; kept across reset(), removed by clear_prior().
  using Prior = std::function<std::optional<geometry::TwoViewPrior>(double reference_s, double current_s)>;
  void set_prior(Prior prior) { prior_ = std::move(prior); }
  void clear_prior() { prior_ = nullptr; }
  void reset();
  [[nodiscard]] bool has_reference() const { return reference_ != nullptr; }
  [[nodiscard]] const map::Frame* reference() const { return reference_.get(); }
  [[nodiscard]] int last_num_matches() const { return last_num_matches_; }
  [[nodiscard]] const MonocularInitializerOptions& options() const { return options_; }

 private:
  void set_reference(const map::Frame& frame);
  // (reference index, current index) pairs; updates previous_positions_ of the matched keypoints.
  std::vector<std::pair<size_t, size_t>> match(const map::Frame& frame);

  MonocularInitializerOptions options_;
  std::shared_ptr<map::Frame> reference_;
  std::vector<cv::Point2f> previous_positions_;  // per reference keypoint
  int last_num_matches_ = 0;
  Prior prior_;
};

// Where a two-view map goes in a map that already holds keyframes (monocular re-anchoring, tracker's
// TrackerOptions::monocular_reanchor): the reference frame's pose and the scale, from the motion tracked
// before the loss. The scale makes the baseline `predicted_baseline` when that is at least
// `min_baseline_share` of `expected_median_depth` (the camera moved enough to measure it), otherwise
// makes the reference's median scene depth `expected_median_depth`.
struct InitialMapPlacement {
  geometry::SE3 reference_cam_from_world;
  double predicted_baseline = 0;
  double expected_median_depth = 1;
  double min_baseline_share = 0.02;
  // The keyframe of the existing map the reference keyframe hangs from in the spanning tree (else the
  // two new keyframes would be each other's parent, a cycle that is never freed).
  std::shared_ptr<map::KeyFrame> parent;
  bool scaled_by_baseline = false;  // output: which of the two fixed the scale
  double scale = 1;                 // output: the scale applied to the two-view reconstruction
};

// The initial map in `map` from a reconstruction whose current frame is `current`: two keyframes, their
// points, bundle adjustment, scaling to median depth 1 (or, with `placement`, placed and scaled as it
// says). On success fills current.cam_from_world and its map point slots and returns the two keyframes
// (reference first); on failure removes what it added (without a placement: leaves `map` empty).
std::optional<std::pair<std::shared_ptr<map::KeyFrame>, std::shared_ptr<map::KeyFrame>>> build_initial_map(
    map::Map& map, const TwoViewInitialization& init, map::Frame& current,
    const MonocularInitializerOptions& options, InitialMapPlacement* placement = nullptr);

}  // namespace crowdslam::tracking
