#include "crowdslam/tracking/dynamic_check.h"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <unordered_set>

#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/pose_refinement.h"
#include "crowdslam/util/error.h"

namespace crowdslam::tracking {
namespace {

constexpr double kChi2Mono = kMatchChi2Mono;
constexpr double kChi2Stereo = kMatchChi2Stereo;

int evaluations(uint8_t history) { return (history >> 4) & 0x3; }
int moving_votes(uint8_t history) {
  const int n = evaluations(history);
  return static_cast<int>(std::bitset<3>(history & ((1u << n) - 1u)).count());
}
uint8_t push_verdict(uint8_t history, bool moving) {
  const int n = std::min(3, evaluations(history) + 1);
  const uint8_t bits = static_cast<uint8_t>(((history << 1) | (moving ? 1 : 0)) & 0x7);
  return static_cast<uint8_t>(bits | (n << 4));
}

using Residual = MatchResidual;
Residual residual(const map::Frame& frame, size_t i, const map::MapPoint& point, const geometry::SE3& pose) {
  return match_residual(frame, i, point, pose);
}

// The frame's residual scale: the median of its matches' chi2, each divided by the median of its
// chi-square distribution (1.386 with 2 dof, 2.366 with 3), at least 1. With residuals as the keypoint
// levels predict it is about 1; with noisier depth or map points made from it (a 5 cm depth noise makes
// every disparity residual large) it grows, and "moving" then means far off by this frame's own noise,
// not by an assumed one. Only trusted matches (trusted_point) give the scale: without the people filter
// on bonn_crowd, people often hold half of a frame's matches, and a median over all of them made every
// threshold large enough to let people through (ATE 0.15-0.86 m against 0.017-0.043 m without the scale).
double residual_scale(const std::vector<Residual>& residuals) {
  if (residuals.size() < 20) return 1.0;  // too few for a median that means anything
  std::vector<double> ratios;
  ratios.reserve(residuals.size());
  for (const Residual& r : residuals) ratios.push_back(r.chi2 / (r.threshold == kChi2Stereo ? 2.366 : 1.386));
  auto mid = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), mid, ratios.end());
  return std::max(1.0, *mid);
}

// Index of the last frame's keypoint matched to each of its points.
std::unordered_map<const map::MapPoint*, size_t> index_points(const map::Frame* last) {
  std::unordered_map<const map::MapPoint*, size_t> index;
  if (!last) return index;
  index.reserve(last->map_points.size());
  for (size_t j = 0; j < last->map_points.size(); ++j) {
    if (last->map_points[j]) index.emplace(last->map_points[j].get(), j);
  }
  return index;
}

}  // namespace

bool DynamicCheck::trusted_point(const map::MapPoint& point) const {
  return point.num_observations() >= options_.trusted_observations && point.motion_score() <= 1;
}

void DynamicCheckOptions::check() const {
  if (!(moving_factor > 0) || !(certain_factor == 0 || certain_factor >= moving_factor)) {
    throw InputError("Geometry: moving_factor must be > 0 and certain_factor 0 or >= moving_factor");
  }
  if (dynamic_score < 1 || cull_score < dynamic_score || cull_score > map::MapPoint::kMotionWindow) {
    throw InputError("Geometry: dynamic_score must be >= 1 and cull_score >= dynamic_score and <= 8");
  }
  if (!(free_space_margin_m >= 0) || !(free_space_ratio >= 0) || free_space_cull_run < 1 ||
      free_space_cull_run > map::MapPoint::kMotionWindow) {
    throw InputError("Geometry: free_space_margin_m and free_space_ratio must be >= 0, free_space_cull_run in [1, 8]");
  }
  if (!(region_radius_px >= 0) || !(region_depth_m >= 0) || !(region_depth_ratio >= 0) || region_steps < 0) {
    throw InputError("Geometry: region_radius_px, region_depth_m, region_depth_ratio and region_steps must be >= 0");
  }
}

DynamicCheck::DynamicCheck(const DynamicCheckOptions& options) : options_(options) { options_.check(); }

void DynamicCheck::inherit(map::Frame& frame, const map::Frame* last) {
  if (!enabled()) return;
  const auto index = index_points(last);
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p) {
      frame.dynamic[i] = false;
      continue;
    }
    bool dynamic = p->num_observations() > 0 && p->motion_score() >= options_.dynamic_score;
    if (!dynamic && last) {
      const auto it = index.find(p.get());
      if (it != index.end()) {
        dynamic = last->dynamic[it->second];
        frame.motion_history[i] = last->motion_history[it->second];
      }
    }
    frame.dynamic[i] = dynamic;
  }
}

int DynamicCheck::screen(map::Frame& frame, const optim::PoseOptimizerOptions& pose_options) const {
  if (!enabled() || options_.min_trusted <= 0 || !frame.cam_from_world) return 0;
  const auto& f = *frame.features;
  std::vector<optim::PoseObservation> trusted;
  size_t candidates = 0;
  for (size_t i = 0; i < frame.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p || frame.dynamic[i] || p->is_bad()) continue;
    ++candidates;
    if (!trusted_point(*p)) continue;
    trusted.push_back({p->world(), geometry::Vec2(f.keys_un[i].pt.x, f.keys_un[i].pt.y), f.right_u[i],
                       frame.levels->inv_sigma2[f.keys_un[i].octave]});
  }
  if (static_cast<int>(trusted.size()) < options_.min_trusted || trusted.size() == candidates) return 0;
  const auto result = optim::optimize_pose(*frame.camera, *frame.cam_from_world, trusted, pose_options);
  if (!result.success || result.num_inliers < options_.min_trusted) return 0;
  frame.cam_from_world = result.cam_from_world;
  std::vector<size_t> slots;
  std::vector<Residual> residuals, of_trusted;
  for (size_t i = 0; i < frame.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p || frame.dynamic[i] || p->is_bad()) continue;
    slots.push_back(i);
    residuals.push_back(residual(frame, i, *p, result.cam_from_world));
    if (trusted_point(*p)) of_trusted.push_back(residuals.back());
  }
  const double scale = residual_scale(of_trusted);
  int screened = 0;
  for (size_t k = 0; k < slots.size(); ++k) {
    if (residuals[k].chi2 > options_.moving_factor * residuals[k].threshold * scale) {
      frame.dynamic[slots[k]] = true;
      ++screened;
    }
  }
  return screened;
}

int DynamicCheck::trusted_inliers(const map::Frame& frame) const {
  int n = 0;
  for (size_t i = 0; i < frame.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (p && !frame.outliers[i] && !frame.dynamic[i] && !p->is_bad() && trusted_point(*p)) ++n;
  }
  return n;
}

DynamicCheckStats DynamicCheck::update(map::Frame& frame, const map::Frame* last) {
  DynamicCheckStats stats;
  if (!enabled() || !frame.cam_from_world) return stats;
  const auto index = index_points(last);
  const geometry::SE3& pose = *frame.cam_from_world;
  std::vector<bool> judged(frame.size(), false);
  // The residuals of the matches that get a verdict (carried from the last frame), computed once: they
  // set the frame's residual scale and then the verdicts.
  std::vector<Residual> residuals(frame.size());
  std::vector<Residual> carried;
  for (size_t i = 0; i < frame.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p || p->is_bad() || !index.count(p.get())) continue;
    residuals[i] = residual(frame, i, *p, pose);
    if (trusted_point(*p)) carried.push_back(residuals[i]);
  }
  const double scale = residual_scale(carried);
  for (size_t i = 0; i < frame.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p) {
      frame.dynamic[i] = false;  // no match, no verdict (region growing may still reach it)
      continue;
    }
    if (p->is_bad()) {  // culled (or merged) meanwhile: keeps what it inherited, and is no tracked point
      if (frame.dynamic[i]) frame.outliers[i] = true;
      continue;
    }
    const bool in_map = p->num_observations() > 0;
    // The history so far: the last frame's keypoint it was matched through, if any.
    uint8_t history = 0;
    bool through_last = false;
    if (last) {
      const auto it = index.find(p.get());
      if (it != index.end()) {
        history = last->motion_history[it->second];
        through_last = true;
      }
    }
    judged[i] = true;
    if (!through_last) {
      // Matched only by the local-map search (wide windows): measured on the static synthetic room, 31 %
      // of these matches are off by more than the threshold against 8 % of the matches carried from the
      // last frame and none of the visual-odometry ones. Such a residual says "wrong match", not "moving":
      // no verdict, the match starts a new history.
      frame.motion_history[i] = 0;
      frame.dynamic[i] = false;
      continue;
    }
    const double chi2 = residuals[i].chi2;
    const double threshold = residuals[i].threshold;
    const bool moving = chi2 > options_.moving_factor * threshold * scale;
    const bool certain = options_.certain_factor > 0 && chi2 > options_.certain_factor * threshold * scale;
    ++stats.checked;
    if (moving) ++stats.moving;
    history = push_verdict(history, moving);
    frame.motion_history[i] = history;
    int score = 0;
    if (in_map) {
      score = p->record_motion(moving);
      if (score >= options_.cull_score) {
        p->set_bad();
        ++stats.points_culled;
      }
    }
    frame.dynamic[i] = certain || moving_votes(history) >= 2 || (in_map && score >= options_.dynamic_score);
    if (frame.dynamic[i]) frame.outliers[i] = true;  // not a tracked static point
  }
  grow_regions(frame, judged, stats);
  stats.dynamic = static_cast<int>(std::count(frame.dynamic.begin(), frame.dynamic.end(), true));
  return stats;
}

void DynamicCheck::grow_regions(map::Frame& frame, const std::vector<bool>& judged, DynamicCheckStats& stats) const {
  if (options_.region_steps == 0 || options_.region_radius_px <= 0) return;
  const auto& f = *frame.features;
  const float radius = static_cast<float>(options_.region_radius_px * f.grid.bounds().width() / 640.0);
  const auto similar_depth = [&](float zs, float zc) {
    if (zs > 0 && zc > 0) return std::abs(zc - zs) <= std::max(options_.region_depth_m, options_.region_depth_ratio * zs);
    return (zs > 0) == (zc > 0);  // one has depth, the other not: no evidence they belong together
  };
  // Seeds: dynamic keypoints with another dynamic keypoint next to them at a similar depth. A moving
  // object shows as a cluster; a lone dynamic verdict (a static point whose map position is off, at a
  // depth edge) does not spread.
  std::vector<size_t> front;
  for (size_t i = 0; i < frame.size(); ++i) {
    if (!frame.dynamic[i]) continue;
    const float r = f.depth_m[i] > 0 ? radius : 0.5f * radius;
    for (const size_t c : f.grid.features_in_area(f.keys_un, f.keys_un[i].pt.x, f.keys_un[i].pt.y, r)) {
      if (c != i && frame.dynamic[c] && similar_depth(f.depth_m[i], f.depth_m[c])) {
        front.push_back(i);
        break;
      }
    }
  }
  for (int step = 0; step < options_.region_steps && !front.empty(); ++step) {
    std::vector<size_t> next;
    for (const size_t s : front) {
      const float zs = f.depth_m[s];
      // Without depth the region is only the image neighbourhood, so keep it tighter.
      const float r = zs > 0 ? radius : 0.5f * radius;
      for (const size_t c : f.grid.features_in_area(f.keys_un, f.keys_un[s].pt.x, f.keys_un[s].pt.y, r)) {
        if (frame.dynamic[c] || judged[c]) continue;  // a keypoint with its own verdict keeps it
        if (!similar_depth(zs, f.depth_m[c])) continue;
        frame.dynamic[c] = true;
        ++stats.grown;
        next.push_back(c);
      }
    }
    front.swap(next);
  }
}

}  // namespace crowdslam::tracking

namespace crowdslam::tracking {

void DynamicCheck::free_space(const map::Frame& frame, const std::vector<std::shared_ptr<map::MapPoint>>& local_points,
                              DynamicCheckStats& stats) const {
  if (!enabled() || !frame.cam_from_world || frame.depth_raw.empty() || frame.depth_raw.type() != CV_16UC1 ||
      options_.free_space_margin_m <= 0) {
    return;
  }
  std::unordered_set<const map::MapPoint*> matched;
  matched.reserve(frame.map_points.size());
  for (const auto& p : frame.map_points) {
    if (p) matched.insert(p.get());
  }
  const geometry::SE3& pose = *frame.cam_from_world;
  const cv::Mat& depth = frame.depth_raw;
  const auto& camera = *frame.camera;
  // A window of 7 x 7 pixels at 640 px: a point at a depth edge whose projection is a pixel or two off
  // still has its own surface somewhere in the window, and then the test says nothing.
  const int radius = std::max(1, static_cast<int>(std::lround(3.0 * depth.cols / 640.0)));
  const int min_valid = (2 * radius + 1) * (2 * radius + 1) / 2;
  for (const auto& p : local_points) {
    if (!p || p->is_bad() || p->num_observations() < 1 || matched.count(p.get())) continue;
    const auto projection = frame.project(*p, 0.5);
    if (!projection) continue;
    const double z = (pose * p->world()).z();
    if (!(z > 0)) continue;
    const geometry::Vec2 raw = camera.distort_pixel({projection->u, projection->v});
    const int cu = static_cast<int>(std::lround(raw.x()));
    const int cv = static_cast<int>(std::lround(raw.y()));
    if (cu - radius < 0 || cv - radius < 0 || cu + radius >= depth.cols || cv + radius >= depth.rows) continue;
    const double beyond = z + std::max(options_.free_space_margin_m, options_.free_space_ratio * z);
    int valid = 0;
    bool through = true;
    for (int y = cv - radius; y <= cv + radius && through; ++y) {
      const auto* row = depth.ptr<uint16_t>(y);
      for (int x = cu - radius; x <= cu + radius; ++x) {
        if (row[x] == 0) continue;
        ++valid;
        if (row[x] * frame.depth_metres_per_unit <= beyond) {
          through = false;
          break;
        }
      }
    }
    if (!through || valid < min_valid) continue;
    ++stats.free_space;
    if (p->record_motion(true) >= options_.cull_score || p->moving_run() >= options_.free_space_cull_run) {
      p->set_bad();
      ++stats.points_culled;
    }
  }
}

}  // namespace crowdslam::tracking
