#include "crowdslam/synth/movers.h"

#include <algorithm>
#include <cmath>

#include "crowdslam/geometry/angles.h"
#include "crowdslam/util/error.h"

namespace crowdslam::synth {
namespace {
using geometry::kPi;

// 0 -> 1 -> 0 over one period, smooth at the turning points (no infinite acceleration).
double back_and_forth(double t, double period_s) {
  return 0.5 - 0.5 * std::cos(2.0 * kPi * t / period_s);
}
}  // namespace

const char* to_string(MoverKind kind) {
  switch (kind) {
    case MoverKind::kSlide: return "slide";
    case MoverKind::kDoor: return "door";
    case MoverKind::kCart: return "cart";
  }
  return "?";
}

Box Mover::box_at(double t) const {
  Box box;
  box.half = half;
  box.mover_id = id;
  const double s = back_and_forth(t, period_s);
  if (kind == MoverKind::kDoor) {
    // The panel's local x axis runs from the hinge along its width.
    const double yaw = base_yaw + s * swing;
    const Eigen::Vector2d along(std::cos(yaw), std::sin(yaw));
    const Eigen::Vector2d centre = start + half.x() * along;
    box.center = {centre.x(), centre.y(), half.z()};
    box.yaw = yaw;
    return box;
  }
  const Eigen::Vector2d centre = start + s * (end - start);
  box.center = {centre.x(), centre.y(), half.z()};
  const Eigen::Vector2d dir = (end - start).normalized();
  box.yaw = std::atan2(dir.y(), dir.x()) + (kind == MoverKind::kCart ? s * swing : 0.0);
  return box;
}

std::pair<Eigen::Vector2d, Eigen::Vector2d> Mover::footprint() const {
  // Sample the motion and bound every corner (exact enough for the people's walk area).
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e9);
  Eigen::Vector2d hi = Eigen::Vector2d::Constant(-1e9);
  for (int k = 0; k <= 64; ++k) {
    const Box b = box_at(period_s * k / 128.0);
    for (const auto& c : b.corners()) {
      lo = lo.cwiseMin(c.head<2>());
      hi = hi.cwiseMax(c.head<2>());
    }
  }
  return {lo, hi};
}

std::vector<Mover> make_movers(int count) {
  if (count < 0 || count > kMaxMovers) {
    throw InputError("--movers: must be between 0 and " + std::to_string(kMaxMovers) + ", got " +
                     std::to_string(count));
  }
  std::vector<Mover> all(kMaxMovers);
  // A crate sliding along the -y wall between the pillar and the sideboard, 0.5 m/s on average.
  all[0].kind = MoverKind::kSlide;
  all[0].half = {0.3, 0.3, 0.5};
  all[0].start = {-1.45, -2.1};
  all[0].end = {-0.05, -2.1};
  all[0].period_s = 5.6;
  // A door in the +x wall: 0.9 m wide, 2 m high, opening 80 degrees into the room every 4 s.
  all[1].kind = MoverKind::kDoor;
  all[1].half = {0.45, 0.03, 1.0};
  all[1].start = {2.96, -0.5};
  all[1].base_yaw = kPi / 2.0;
  all[1].swing = 80.0 * kPi / 180.0;
  all[1].period_s = 4.0;
  // A cart driving along the +y side, turning 60 degrees over its path.
  all[2].kind = MoverKind::kCart;
  all[2].half = {0.3, 0.25, 0.45};
  all[2].start = {-0.9, 1.55};
  all[2].end = {1.2, 1.55};
  all[2].swing = 60.0 * kPi / 180.0;
  all[2].period_s = 7.0;
  // A second door in the -x wall, swinging the other way.
  all[3].kind = MoverKind::kDoor;
  all[3].half = {0.45, 0.03, 1.0};
  all[3].start = {-2.96, -1.25};
  all[3].base_yaw = kPi / 2.0;
  all[3].swing = -75.0 * kPi / 180.0;
  all[3].period_s = 5.0;
  all.resize(count);
  for (int i = 0; i < count; ++i) all[i].id = i + 1;
  return all;
}

}  // namespace crowdslam::synth
