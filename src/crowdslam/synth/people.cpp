#include "crowdslam/synth/people.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "crowdslam/geometry/angles.h"
#include "crowdslam/synth/rng.h"
#include "crowdslam/synth/options.h"

namespace crowdslam::synth {
namespace {

using geometry::kPi;
constexpr double kBodyRadiusM = 0.28;      // circle around the body footprint
constexpr double kWallMarginM = 0.1;
constexpr double kPersonSpacingM = 0.7;   // between body centres
constexpr double kMaxTurnPerFrame = 8.0 * kPi / 180.0;
const int kLookAheadFrames[] = {1, 6, 12, 20};

class Walker {
 public:
  Walker(const io::Trajectory& camera, const WalkArea& area) : camera_(camera), area_(area) {}

  // Clearance of a body centre at `frame`: negative when the spot is not allowed.
  double score(const Eigen::Vector2d& p, int frame, const std::vector<Eigen::Vector2d>& others) const {
    const double r = kBodyRadiusM + kWallMarginM;
    if (p.x() < area_.min_corner.x() + r || p.x() > area_.max_corner.x() - r ||
        p.y() < area_.min_corner.y() + r || p.y() > area_.max_corner.y() - r) {
      return -1.0;
    }
    for (const auto& [lo, hi] : area_.obstacles) {
      if (p.x() > lo.x() - r && p.x() < hi.x() + r && p.y() > lo.y() - r && p.y() < hi.y() + r) return -1.0;
    }
    for (const auto& q : others) {
      if ((p - q).norm() < kPersonSpacingM) return -1.0;
    }
    double clearance = std::numeric_limits<double>::infinity();
    for (int ahead : kLookAheadFrames) {
      const int f = std::min(frame + ahead - 1, static_cast<int>(camera_.size()) - 1);
      const Eigen::Vector2d c = camera_[f].world_from_cam.translation().head<2>();
      clearance = std::min(clearance, (p - c).norm() - kBodyRadiusM - kMinCameraClearanceM - 0.05);
    }
    return clearance;
  }

  // A spot 1.5-3 m in front of the camera at `frame`: people head there half the time, so they keep
  // crossing the view as in a crowd.
  Eigen::Vector2d view_target(int frame, Rng& rng) const {
    const geometry::SE3& pose = camera_[std::min(frame, static_cast<int>(camera_.size()) - 1)].world_from_cam;
    const Eigen::Vector3d forward = pose.rotation_matrix().col(2);
    const Eigen::Vector3d right = pose.rotation_matrix().col(0);
    const Eigen::Vector3d target = pose.translation() + rng.uniform(1.5, 3.0) * forward + rng.uniform(-1.0, 1.0) * right;
    const double margin = 0.6;
    return {std::clamp(target.x(), area_.min_corner.x() + margin, area_.max_corner.x() - margin),
            std::clamp(target.y(), area_.min_corner.y() + margin, area_.max_corner.y() - margin)};
  }

 private:
  const io::Trajectory& camera_;
  const WalkArea& area_;
};

struct Walking {
  Eigen::Vector2d position;
  double heading = 0.0;
  double body_yaw = 0.0;
  double left_on_segment_m = 0.0;
};

double wrap_angle(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a < -kPi) a += 2 * kPi;
  return a;
}

Eigen::Vector2d step_from(const Eigen::Vector2d& p, double heading, double length) {
  return p + length * Eigen::Vector2d(std::cos(heading), std::sin(heading));
}

// Moves one person one frame: straight on while allowed, else the first allowed random heading, else
// the heading (or standing still) that best keeps away from the camera.
void advance(Walking& w, double step_m, int frame, const std::vector<Eigen::Vector2d>& others,
             const Walker& walker, Rng& rng) {
  w.left_on_segment_m -= step_m;
  bool turn = w.left_on_segment_m <= 0.0;
  if (!turn && walker.score(step_from(w.position, w.heading, step_m), frame, others) < 0.0) turn = true;
  if (turn) {
    w.left_on_segment_m = rng.uniform(1.5, 5.0);
    double best_heading = w.heading;
    double best_score = -std::numeric_limits<double>::infinity();
    bool found = false;
    const bool to_view = rng.uniform() < 0.5;
    const Eigen::Vector2d target = walker.view_target(frame, rng);
    for (int attempt = 0; attempt < 24 && !found; ++attempt) {
      const Eigen::Vector2d to_target = target - w.position;
      const double heading = (attempt == 0 && to_view) ? std::atan2(to_target.y(), to_target.x()) : rng.uniform(-kPi, kPi);
      const double s = walker.score(step_from(w.position, heading, step_m), frame, others);
      if (s >= 0.0) {
        found = true;
        if (attempt == 0 && to_view) w.left_on_segment_m = std::max(0.5, to_target.norm());
      }
      if (s > best_score) {
        best_score = s;
        best_heading = heading;
      }
    }
    w.heading = best_heading;
    if (!found && walker.score(w.position, frame, others) >= best_score) {
      step_m = 0.0;  // nowhere better to go: wait
    }
  }
  w.position = step_from(w.position, w.heading, step_m);
  const double turn_by = std::clamp(wrap_angle(w.heading - w.body_yaw), -kMaxTurnPerFrame, kMaxTurnPerFrame);
  w.body_yaw = wrap_angle(w.body_yaw + turn_by);
}

Eigen::Vector2d initial_position(const WalkArea& area, const Walker& walker,
                                 const std::vector<Eigen::Vector2d>& others, Rng& rng) {
  Eigen::Vector2d best = 0.5 * (area.min_corner + area.max_corner);
  double best_score = -std::numeric_limits<double>::infinity();
  for (int attempt = 0; attempt < 400; ++attempt) {
    const Eigen::Vector2d p(rng.uniform(area.min_corner.x(), area.max_corner.x()),
                            rng.uniform(area.min_corner.y(), area.max_corner.y()));
    const double s = walker.score(p, 0, others);
    if (s >= 0.5) return p;  // well away from the camera at the start
    if (s > best_score) {
      best_score = s;
      best = p;
    }
  }
  return best;
}

}  // namespace

const char* to_string(PersonRole role) {
  switch (role) {
    case PersonRole::kWalker:
      return "walker";
    case PersonRole::kGroup:
      return "group";
    case PersonRole::kNear:
      return "near";
    case PersonRole::kBlackout:
      return "blackout";
  }
  return "walker";
}

std::vector<PersonTrack> simulate_people(int count, const io::Trajectory& camera, const WalkArea& area,
                                         std::uint64_t seed) {
  std::vector<PersonTrack> tracks(count);
  if (count == 0 || camera.empty()) return tracks;
  Rng rng(seed, 0x9e09);
  const Walker walker(camera, area);
  std::vector<Walking> walking(count);
  std::vector<Eigen::Vector2d> placed;
  for (int i = 0; i < count; ++i) {
    tracks[i].id = i + 1;
    tracks[i].speed_mps = rng.uniform(0.5, 1.2);
    walking[i].position = initial_position(area, walker, placed, rng);
    walking[i].heading = rng.uniform(-kPi, kPi);
    walking[i].body_yaw = walking[i].heading;
    walking[i].left_on_segment_m = rng.uniform(1.0, 4.0);
    placed.push_back(walking[i].position);
  }
  const int frames = static_cast<int>(camera.size());
  for (int f = 0; f < frames; ++f) {
    for (int i = 0; i < count; ++i) {
      if (f > 0) {
        std::vector<Eigen::Vector2d> others;
        for (int j = 0; j < count; ++j) {
          if (j != i) others.push_back(walking[j].position);
        }
        advance(walking[i], tracks[i].speed_mps / kFps, f, others, walker, rng);
      }
      tracks[i].states.push_back({walking[i].position, walking[i].body_yaw});
    }
  }
  return tracks;
}

Box person_box(const PersonState& state, int person_id) {
  Box box;
  box.center = {state.position.x(), state.position.y(), kPersonHeightM / 2.0};
  box.half = {kPersonWidthM / 2.0, kPersonDepthM / 2.0, kPersonHeightM / 2.0};
  box.yaw = state.body_yaw - kPi / 2.0;  // local +y is the walking direction, local x the shoulders
  box.person_id = person_id;
  return box;
}

double distance_to_person(const PersonState& state, const Eigen::Vector2d& point) {
  const Box box = person_box(state, 1);
  const Eigen::Vector3d local = box.to_local({point.x(), point.y(), box.center.z()});
  const double dx = std::max(0.0, std::abs(local.x()) - box.half.x());
  const double dy = std::max(0.0, std::abs(local.y()) - box.half.y());
  return std::hypot(dx, dy);
}

}  // namespace crowdslam::synth
