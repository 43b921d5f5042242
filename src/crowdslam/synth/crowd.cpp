#include "crowdslam/synth/crowd.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "crowdslam/geometry/angles.h"
#include "crowdslam/synth/rng.h"

namespace crowdslam::synth {
// Named, not anonymous: the library is built in unity batches, where anonymous namespaces of
// several files are one.
namespace crowd_sim {

using geometry::kPi;
using V2 = Eigen::Vector2d;
constexpr double kBodyRadiusM = 0.28;
constexpr double kWallMarginM = 0.1;
constexpr double kMaxTurnPerFrame = 8.0 * kPi / 180.0;
constexpr double kInvalid = -10.0;  // score of a spot nobody may step on (walls, obstacles, other people)
const int kLookAheadFrames[] = {1, 6, 12, 20};
constexpr double kGroupChordM = 0.65;          // between neighbours on a group's circle
constexpr double kGroupCameraDistanceM = 0.7;  // a group member's centre from the camera centre, at least
constexpr double kSwayM = 0.02;
// Blackout: formation in the camera's horizontal frame (metres ahead, metres to the right), the lateral
// sweep (enters from kSweepM to one side, covers the view while drifting by +-kDriftM, leaves to the
// other side) and its speed relative to the camera.
const double kFormation[][2] = {{0.5, -0.22}, {0.5, 0.22}, {0.85, -0.45}, {0.85, 0.0},
                                {0.85, 0.45}, {1.2, -0.3}, {1.2, 0.3}};
constexpr int kMaxBlackout = 7;
constexpr double kSweepM = 1.6;
constexpr double kDriftM = 0.15;
constexpr double kSweepSpeedMps = 1.3;

struct Params {
  double to_view = 0.8;      // probability that a walker's next leg crosses the view
  double stops_per_s = 0.1;  // how often a walking walker stops (for 1-4 s)
  int groups = 0;            // people standing in groups
  int near = 0;              // near crossers
  int blackout = 0;          // the blackout group
};

Params params_for(CrowdProfile profile, int count) {
  Params p;
  switch (profile) {
    case CrowdProfile::kStanding:
      p.to_view = 0.5;
      p.stops_per_s = 0.2;
      p.groups = count >= 2 ? std::max(2, static_cast<int>(std::lround(0.75 * count))) : 0;
      break;
    case CrowdProfile::kNear:
      p.near = count > 0 ? std::max(1, static_cast<int>(std::lround(count / 3.0))) : 0;
      break;
    case CrowdProfile::kBlackout:
      p.blackout = std::min(count, kMaxBlackout);
      break;
    default:
      break;
  }
  return p;
}

double wrap_angle(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a < -kPi) a += 2 * kPi;
  return a;
}

V2 step_from(const V2& p, double heading, double length) {
  return p + length * V2(std::cos(heading), std::sin(heading));
}

// The floor, the obstacles and the camera: where a body centre may be.
class Floor {
 public:
  Floor(const io::Trajectory& camera, const WalkArea& area) : camera_(camera), area_(area) {}

  int frames() const { return static_cast<int>(camera_.size()); }
  bool on_floor(const V2& p, double extra = 0.0) const {
    const double r = kBodyRadiusM + kWallMarginM + extra;
    if (p.x() < area_.min_corner.x() + r || p.x() > area_.max_corner.x() - r ||
        p.y() < area_.min_corner.y() + r || p.y() > area_.max_corner.y() - r) {
      return false;
    }
    for (const auto& [lo, hi] : area_.obstacles) {
      if (p.x() > lo.x() - r && p.x() < hi.x() + r && p.y() > lo.y() - r && p.y() < hi.y() + r) return false;
    }
    return true;
  }
  V2 clamp_to_room(const V2& p, double extra = 0.0) const {
    const double r = kBodyRadiusM + kWallMarginM + extra;
    return {std::clamp(p.x(), area_.min_corner.x() + r, area_.max_corner.x() - r),
            std::clamp(p.y(), area_.min_corner.y() + r, area_.max_corner.y() - r)};
  }
  V2 camera(int frame) const { return camera_[clamp_frame(frame)].world_from_cam.translation().head<2>(); }
  // Horizontal unit view direction and its right.
  V2 forward(int frame) const {
    const Eigen::Vector3d f = camera_[clamp_frame(frame)].world_from_cam.rotation_matrix().col(2);
    const V2 h(f.x(), f.y());
    return h.norm() > 1e-9 ? V2(h.normalized()) : V2(1.0, 0.0);
  }
  V2 right(int frame) const {
    const V2 f = forward(frame);
    return {f.y(), -f.x()};
  }
  // How far the spot stays beyond `distance` from the camera over the next frames (negative: too close).
  double camera_clearance(const V2& p, int frame, double distance) const {
    double clearance = std::numeric_limits<double>::infinity();
    for (int ahead : kLookAheadFrames)
      clearance = std::min(clearance, (p - camera(frame + ahead - 1)).norm() - distance);
    return clearance;
  }
  double score(const V2& p, int frame, const std::vector<V2>& others, double distance) const {
    if (!on_floor(p)) return kInvalid;
    for (const V2& q : others) {
      if ((p - q).norm() < kCrowdSpacingM) return kInvalid;
    }
    return camera_clearance(p, frame, distance);
  }

 private:
  int clamp_frame(int f) const { return std::clamp(f, 0, frames() - 1); }
  const io::Trajectory& camera_;
  const WalkArea& area_;
};

struct Agent {
  PersonRole role = PersonRole::kWalker;
  double speed = 0.0;
  V2 position = V2::Zero();
  double heading = 0.0;
  double body_yaw = 0.0;
  double left_m = 0.0;  // of the current leg
  int wait = 0;         // frames left standing still
};

// Where a walker's leg across the view ends: ahead of the camera, on the other side of it.
V2 crossing_target(const Floor& floor, const V2& from, int frame, Rng& rng) {
  const V2 c = floor.camera(frame);
  const double side = (from - c).dot(floor.right(frame)) > 0.0 ? -1.0 : 1.0;
  const double ahead = rng.uniform(1.3, 3.0);
  const double across = side * rng.uniform(0.8, 2.0);
  return floor.clamp_to_room(c + ahead * floor.forward(frame) + across * floor.right(frame), 0.3);
}

// Where a near crosser heads: just in front of where the camera will be when it gets there (it walks on
// past it).
V2 near_target(const Floor& floor, const Agent& a, int frame, Rng& rng) {
  const double ahead = rng.uniform(0.45, 0.8);
  const double across = rng.uniform(-0.2, 0.2);
  const int lead = static_cast<int>((a.position - floor.camera(frame)).norm() / a.speed * kFps);
  const int f = frame + lead;
  return floor.camera(f) + ahead * floor.forward(f) + across * floor.right(f);
}

void step_walker(Agent& a, int frame, const std::vector<V2>& others, const Floor& floor, const Params& params,
                 Rng& rng) {
  const double distance = a.role == PersonRole::kNear ? kNearCameraDistanceM : kWalkerCameraDistanceM;
  double step = a.speed / kFps;
  if (a.wait > 0) {
    --a.wait;
    if (floor.score(a.position, frame, others, distance) >= 0.0) return;
    a.wait = 0;  // the camera or somebody comes: walk on
  }
  // Now and then a walker stops for 1-4 s (where it may stand).
  if (rng.uniform() < params.stops_per_s / kFps && floor.score(a.position, frame, others, distance) >= 0.0) {
    a.wait = static_cast<int>(kFps * rng.uniform(1.0, 4.0));
    return;
  }
  a.left_m -= step;
  if (a.left_m <= 0.0 || floor.score(step_from(a.position, a.heading, step), frame, others, distance) < 0.0) {
    a.left_m = rng.uniform(1.5, 5.0);
    const bool near = a.role == PersonRole::kNear;
    const bool to_view = rng.uniform() < (near ? 0.9 : params.to_view);
    const V2 target =
        near ? near_target(floor, a, frame, rng) : crossing_target(floor, a.position, frame, rng);
    double best_heading = a.heading;
    double best_score = -std::numeric_limits<double>::infinity();
    bool found = false;
    for (int attempt = 0; attempt < 24 && !found; ++attempt) {
      const V2 to_target = target - a.position;
      const bool aimed = attempt == 0 && to_view;
      const double heading = aimed ? std::atan2(to_target.y(), to_target.x()) : rng.uniform(-kPi, kPi);
      const double s = floor.score(step_from(a.position, heading, step), frame, others, distance);
      if (s >= 0.0) {
        found = true;
        // A near crosser aims again every 0.8 m until close, then walks on past the camera.
        if (aimed) {
          const double d = to_target.norm();
          a.left_m = !near ? std::max(0.5, d) : (d > 1.2 ? 0.8 : d + rng.uniform(1.0, 2.0));
        }
      }
      if (s > best_score) {
        best_score = s;
        best_heading = heading;
      }
    }
    a.heading = best_heading;
    if (!found && floor.score(a.position, frame, others, distance) >= best_score) step = 0.0;  // wait
  }
  a.position = step_from(a.position, a.heading, step);
  const double turn_by = std::clamp(wrap_angle(a.heading - a.body_yaw), -kMaxTurnPerFrame, kMaxTurnPerFrame);
  a.body_yaw = wrap_angle(a.body_yaw + turn_by);
}

// A scripted person's positions for every frame (groups, the blackout group).
using Script = std::vector<PersonState>;

struct GroupPlan {
  V2 centre;
  int size = 0;
  double radius = 0.0;
};

// Groups of 2-4 (sizes drawn until `people` are placed), each on a free spot the camera passes within
// 3 m of but never closer than kGroupCameraDistanceM to a member. Returns the groups placed.
std::vector<GroupPlan> plan_groups(int people, const Floor& floor, Rng& rng) {
  std::vector<int> sizes;
  for (int left = people; left > 0;) {
    int n = std::min(left, 2 + rng.below(3));
    if (left - n == 1) n = n < 4 ? n + 1 : n - 1;
    if (n < 2) break;
    sizes.push_back(n);
    left -= n;
  }
  std::vector<GroupPlan> groups;
  for (int n : sizes) {
    GroupPlan g;
    g.size = n;
    g.radius = 0.5 * kGroupChordM / std::sin(kPi / n);
    bool placed = false;
    for (int attempt = 0; attempt < 600 && !placed; ++attempt) {
      const V2 lo = floor.clamp_to_room(V2(-1e9, -1e9));
      const V2 hi = floor.clamp_to_room(V2(1e9, 1e9));
      g.centre = {rng.uniform(lo.x(), hi.x()), rng.uniform(lo.y(), hi.y())};
      bool ok = true;
      for (int i = 0; i < n && ok; ++i) {
        const double a = 2.0 * kPi * i / n;
        ok = floor.on_floor(g.centre + g.radius * V2(std::cos(a), std::sin(a)), kSwayM);
      }
      for (const GroupPlan& other : groups) {
        ok = ok && (g.centre - other.centre).norm() >= g.radius + other.radius + kCrowdSpacingM + 0.2;
      }
      double closest = std::numeric_limits<double>::infinity();
      for (int f = 0; f < floor.frames() && ok; f += 2)
        closest = std::min(closest, (g.centre - floor.camera(f)).norm());
      ok = ok && closest >= g.radius + kSwayM + kGroupCameraDistanceM &&
           (closest <= g.radius + 3.0 || attempt >= 300);
      placed = ok;
    }
    if (placed) groups.push_back(g);
  }
  return groups;
}

Script group_member_script(const GroupPlan& g, int member, double phase0, int frames, Rng& rng) {
  const double a = phase0 + 2.0 * kPi * member / g.size;
  const V2 slot = g.centre + g.radius * V2(std::cos(a), std::sin(a));
  const double period_s = rng.uniform(3.0, 6.0);
  const double sway_phase = rng.uniform(0.0, 2.0 * kPi);
  Script s(frames);
  for (int f = 0; f < frames; ++f) {
    const double w = 2.0 * kPi * f / (kFps * period_s) + sway_phase;
    s[f].position = slot + kSwayM * V2(std::sin(w), std::cos(w));
    s[f].body_yaw = a + kPi;  // facing the group's centre
  }
  return s;
}

struct BlackoutPlan {
  int start = 0;  // first frame of the event (the group enters the view from the side)
  int approach = 0, cover = 0, leave = 0;
  double side = 1.0;  // the side it enters from (+1: the camera's right)
};

// The group's lateral offset (metres to the camera's right) at frame k of the event.
double sweep_offset(const BlackoutPlan& p, int k) {
  if (k < p.approach) return p.side * (kSweepM - (kSweepM - kDriftM) * k / p.approach);
  if (k < p.approach + p.cover) return p.side * (kDriftM - 2.0 * kDriftM * (k - p.approach) / p.cover);
  return -p.side * (kDriftM + (kSweepM - kDriftM) *
                                  std::min(1.0, static_cast<double>(k - p.approach - p.cover) / p.leave));
}

V2 formation_position(const Floor& floor, const BlackoutPlan& p, int member, int frame) {
  const int k = std::clamp(frame - p.start, 0, p.approach + p.cover + p.leave - 1);
  const int f = p.start + k;
  const V2 spot = floor.camera(f) + kFormation[member][0] * floor.forward(f) +
                  (kFormation[member][1] + sweep_offset(p, k)) * floor.right(f);
  return floor.clamp_to_room(spot);
}

// The event's start and side: in the middle of the sequence where the group, standing before and after,
// keeps farthest from the camera (at least kWalkerCameraDistanceM when possible).
BlackoutPlan plan_blackout(const Floor& floor, int members, Rng& rng) {
  BlackoutPlan p;
  p.approach = static_cast<int>(std::ceil((kSweepM - kDriftM) / kSweepSpeedMps * kFps));
  p.leave = p.approach;
  p.cover = static_cast<int>(std::lround(kBlackoutSeconds * kFps));
  const int length = p.approach + p.cover + p.leave;
  const int frames = floor.frames();
  const int first = std::max(0, static_cast<int>(0.3 * frames) - p.approach);
  const int last = std::max(first, std::min(frames - length, static_cast<int>(0.6 * frames)));
  BlackoutPlan best = p;
  double best_clearance = -std::numeric_limits<double>::infinity();
  const int offset = rng.below(3);
  for (int start = first + offset; start <= last; start += 3) {
    for (double side : {1.0, -1.0}) {
      BlackoutPlan c = p;
      c.start = start;
      c.side = side;
      double clearance = std::numeric_limits<double>::infinity();
      for (int m = 0; m < members; ++m) {
        const V2 before = formation_position(floor, c, m, start);
        const V2 after = formation_position(floor, c, m, start + length - 1);
        for (int f = 0; f < frames; f += 2) {
          if (f >= start && f < start + length) continue;
          clearance = std::min(clearance, ((f < start ? before : after) - floor.camera(f)).norm());
        }
      }
      if (clearance > best_clearance + 1e-9) {
        best_clearance = clearance;
        best = c;
      }
    }
    if (best_clearance >= kWalkerCameraDistanceM + 0.2) break;
  }
  return best;
}

Script blackout_script(const Floor& floor, const BlackoutPlan& p, int member) {
  Script s(floor.frames());
  double yaw = p.side > 0 ? 0.0 : kPi;
  for (int f = 0; f < floor.frames(); ++f) {
    s[f].position = formation_position(floor, p, member, f);
    if (f > 0) {
      const V2 d = s[f].position - s[f - 1].position;
      if (d.norm() > 1e-3) yaw = std::atan2(d.y(), d.x());
    }
    s[f].body_yaw = yaw;
  }
  return s;
}

}  // namespace crowd_sim

Crowd simulate_crowd(CrowdProfile profile, int count, const io::Trajectory& camera, const WalkArea& area,
                     std::uint64_t seed) {
  using namespace crowd_sim;
  assert(profile != CrowdProfile::kAuto && profile != CrowdProfile::kWalk);
  Crowd crowd;
  crowd.people.resize(count);
  if (count == 0 || camera.empty()) return crowd;
  const int frames = static_cast<int>(camera.size());
  Rng rng(seed, 0xc20d);
  const Floor floor(camera, area);
  const Params params = params_for(profile, count);
  // Scripted people first (ids 1..), then the walkers.
  std::vector<Script> scripts;
  std::vector<PersonRole> roles;
  if (params.blackout > 0) {
    const BlackoutPlan plan = plan_blackout(floor, params.blackout, rng);
    crowd.blackout_first = plan.start + plan.approach;
    crowd.blackout_last = std::min(frames - 1, plan.start + plan.approach + plan.cover - 1);
    for (int m = 0; m < params.blackout; ++m) {
      scripts.push_back(blackout_script(floor, plan, m));
      roles.push_back(PersonRole::kBlackout);
    }
  }
  if (params.groups > 0) {
    for (const GroupPlan& g : plan_groups(params.groups, floor, rng)) {
      const double phase0 = rng.uniform(0.0, 2.0 * kPi);
      for (int m = 0; m < g.size; ++m) {
        scripts.push_back(group_member_script(g, m, phase0, frames, rng));
        roles.push_back(PersonRole::kGroup);
      }
    }
  }
  const int scripted = static_cast<int>(scripts.size());
  std::vector<Agent> agents(count - scripted);
  for (int i = 0; i < count; ++i) {
    crowd.people[i].id = i + 1;
    crowd.people[i].role =
        i < scripted ? roles[i] : (i - scripted < params.near ? PersonRole::kNear : PersonRole::kWalker);
    crowd.people[i].states.reserve(frames);
  }
  // Walkers start on free spots, well away from the camera when there is room.
  std::vector<V2> placed;
  for (const Script& s : scripts) placed.push_back(s[0].position);
  for (size_t a = 0; a < agents.size(); ++a) {
    Agent& agent = agents[a];
    PersonTrack& track = crowd.people[scripted + a];
    agent.role = track.role;
    agent.speed = agent.role == PersonRole::kNear ? rng.uniform(0.8, 1.3) : rng.uniform(0.5, 1.2);
    track.speed_mps = agent.speed;
    const double distance = agent.role == PersonRole::kNear ? kNearCameraDistanceM : kWalkerCameraDistanceM;
    double best_score = -std::numeric_limits<double>::infinity();
    const V2 lo = floor.clamp_to_room(V2(-1e9, -1e9));
    const V2 hi = floor.clamp_to_room(V2(1e9, 1e9));
    for (int attempt = 0; attempt < 1000; ++attempt) {
      const double x = rng.uniform(lo.x(), hi.x());
      const V2 p(x, rng.uniform(lo.y(), hi.y()));
      const double s = floor.score(p, 0, placed, distance);
      if (s > best_score) {
        best_score = s;
        agent.position = p;
      }
      if (s >= 0.5) break;
    }
    agent.heading = rng.uniform(-kPi, kPi);
    agent.body_yaw = agent.heading;
    agent.left_m = rng.uniform(1.0, 4.0);
    placed.push_back(agent.position);
  }
  std::vector<V2> others;
  for (int f = 0; f < frames; ++f) {
    for (int i = 0; i < scripted; ++i) crowd.people[i].states.push_back(scripts[i][f]);
    for (size_t a = 0; a < agents.size(); ++a) {
      if (f > 0) {
        others.clear();
        for (int i = 0; i < scripted; ++i) others.push_back(scripts[i][f].position);
        for (size_t b = 0; b < agents.size(); ++b) {
          if (b != a) others.push_back(agents[b].position);
        }
        step_walker(agents[a], f, others, floor, params, rng);
      }
      crowd.people[scripted + a].states.push_back({agents[a].position, agents[a].body_yaw});
    }
  }
  for (int i = 0; i < scripted; ++i) {
    double walked = 0.0;
    for (int f = 1; f < frames; ++f) walked += (scripts[i][f].position - scripts[i][f - 1].position).norm();
    crowd.people[i].speed_mps = frames > 1 ? walked / ((frames - 1) / kFps) : 0.0;
  }
  return crowd;
}

}  // namespace crowdslam::synth
