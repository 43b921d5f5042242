#include "crowdslam/tracking/localize_frames.h"

#include <algorithm>

#include "crowdslam/map/map_point.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/tracking/pose_refinement.h"

namespace crowdslam::tracking {

geometry::SE3 interpolate_pose(const geometry::SE3& a, const geometry::SE3& b, double t) {
  const geometry::SE3 wa = a.inverse();
  const geometry::SE3 wb = b.inverse();
  const Eigen::Quaterniond q = wa.rotation().slerp(t, wb.rotation());
  const geometry::Vec3 c = (1 - t) * wa.translation() + t * wb.translation();
  return geometry::SE3(q, c).inverse();
}

int match_projected_and_optimize(map::Frame& frame, const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                 double radius_factor, const optim::PoseOptimizerOptions& options) {
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  std::vector<match::ProjectedPoint> projected;
  projected.reserve(points.size());
  for (const auto& p : points) {
    if (!p || p->is_bad()) continue;
    if (auto projection = frame.project(*p, 0.5)) projected.push_back({p, *projection});
  }
  if (projected.empty()) return 0;
  match::search_local_points(frame, projected, radius_factor);
  return optimize_frame_pose(frame, options);
}

void keep_last_frames(std::deque<map::Frame>& frames, const map::Frame& frame, size_t max) {
  frames.push_back(frame);
  while (frames.size() > max) frames.pop_front();
}

std::optional<geometry::SE3> localize_in_map(map::Frame frame, const geometry::SE3& guess,
                                             const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                             const optim::PoseOptimizerOptions& options) {
  constexpr int kMinInliers = 50;
  frame.cam_from_world = guess;
  for (const double radius_factor : {6.0, 1.5}) {
    if (match_projected_and_optimize(frame, points, radius_factor, options) < kMinInliers) return std::nullopt;
  }
  return frame.cam_from_world;
}

FramePoses localize_backwards(std::deque<map::Frame>& frames, geometry::SE3& later, geometry::SE3& step,
                              const std::vector<std::shared_ptr<map::MapPoint>>& points,
                              const optim::PoseOptimizerOptions& options, double max_gap_s) {
  FramePoses recovered;
  std::deque<map::Frame> failed;  // skipped over, oldest first
  geometry::SE3 guess_from = later;
  bool gap = false;
  double last_t = frames.empty() ? 0.0 : frames.back().timestamp_s;  // of the last frame localised
  while (!frames.empty()) {
    const geometry::SE3 guess = step * guess_from;
    const auto pose = localize_in_map(frames.back(), guess, points, options);
    if (!pose) {
      if (!(last_t - frames.back().timestamp_s < max_gap_s)) break;
      // Skipped: the next earlier frame is guessed on from here by the same step.
      gap = true;
      guess_from = guess;
      failed.push_front(std::move(frames.back()));
      frames.pop_back();
      continue;
    }
    // A step is measured only between neighbouring frames; over a gap the last one stays.
    if (!gap) step = *pose * later.inverse();
    later = *pose;
    guess_from = later;
    gap = false;
    last_t = frames.back().timestamp_s;
    recovered.emplace_back(frames.back().id, *pose);
    frames.pop_back();
  }
  // What is left, oldest first: the frames not tried and those skipped.
  for (auto& f : failed) frames.push_back(std::move(f));
  return recovered;
}

AroundTwoViews localize_around_two_views(std::deque<map::Frame> frames, uint64_t reference_id,
                                         const geometry::SE3& first_pose, double t0,
                                         const geometry::SE3& last_pose, double t1,
                                         const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                         const optim::PoseOptimizerOptions& options, double max_gap_s) {
  AroundTwoViews out;
  // Between the reference frame and the second view.
  for (const auto& frame : frames) {
    if (frame.id <= reference_id || t1 <= t0) continue;
    const double t = std::clamp((frame.timestamp_s - t0) / (t1 - t0), 0.0, 1.0);
    if (auto pose = localize_in_map(frame, interpolate_pose(first_pose, last_pose, t), points, options)) {
      out.recovered.emplace_back(frame.id, *pose);
    }
  }
  // Before the reference frame, newest first.
  for (auto& frame : frames) {
    if (frame.id < reference_id) out.left.push_back(std::move(frame));
  }
  // The first step back: the motion between the two views, extrapolated by time to the frame before.
  out.later = first_pose;
  if (!out.left.empty() && t1 > t0) {
    const double t = (out.left.back().timestamp_s - t0) / (t1 - t0);
    out.step = interpolate_pose(first_pose, last_pose, std::max(t, -1.0)) * first_pose.inverse();
  }
  const auto before = localize_backwards(out.left, out.later, out.step, points, options, max_gap_s);
  out.recovered.insert(out.recovered.end(), before.begin(), before.end());
  std::sort(out.recovered.begin(), out.recovered.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

}  // namespace crowdslam::tracking
