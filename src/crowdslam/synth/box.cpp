#include "crowdslam/synth/box.h"

#include <cmath>
#include <limits>

#include "crowdslam/synth/textures.h"

namespace crowdslam::synth {

Box Box::axis_aligned(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner) {
  Box box;
  box.center = 0.5 * (min_corner + max_corner);
  box.half = 0.5 * (max_corner - min_corner);
  return box;
}

std::array<Eigen::Vector3d, 8> Box::corners() const {
  std::array<Eigen::Vector3d, 8> out;
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  for (int i = 0; i < 8; ++i) {
    const double x = (i & 1) ? half.x() : -half.x();
    const double y = (i & 2) ? half.y() : -half.y();
    const double z = (i & 4) ? half.z() : -half.z();
    out[i] = center + Eigen::Vector3d(c * x - s * y, s * x + c * y, z);
  }
  return out;
}

Eigen::Vector3d Box::to_local(const Eigen::Vector3d& world_point) const {
  return dir_to_local(world_point - center);
}

Eigen::Vector3d Box::dir_to_local(const Eigen::Vector3d& d) const {
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z()};
}

Eigen::Vector3d Box::face_normal(int face) const {
  const int axis = face / 2;
  const double sign = ((face % 2) ? 1.0 : -1.0) * (inside ? -1.0 : 1.0);
  Eigen::Vector3d local = Eigen::Vector3d::Zero();
  local[axis] = sign;
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  return {c * local.x() - s * local.y(), s * local.x() + c * local.y(), local.z()};
}

std::optional<BoxHit> intersect_local(const Box& box, const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& dir, double t_min) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double t_near = -kInf;
  double t_far = kInf;
  int face_near = 0;
  int face_far = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double o = origin[axis];
    const double d = dir[axis];
    const double h = box.half[axis];
    if (d == 0.0) {
      if (o < -h || o > h) return std::nullopt;
      continue;
    }
    const double inv = 1.0 / d;
    double t0 = (-h - o) * inv;  // plane of the -axis face
    double t1 = (h - o) * inv;   // plane of the +axis face
    int f0 = 2 * axis;
    int f1 = 2 * axis + 1;
    if (t0 > t1) {
      std::swap(t0, t1);
      std::swap(f0, f1);
    }
    if (t0 > t_near) {
      t_near = t0;
      face_near = f0;
    }
    if (t1 < t_far) {
      t_far = t1;
      face_far = f1;
    }
  }
  if (t_near > t_far) return std::nullopt;
  if (box.inside) {
    if (t_far <= t_min) return std::nullopt;
    return BoxHit{t_far, face_far};
  }
  if (t_near <= t_min) return std::nullopt;
  return BoxHit{t_near, face_near};
}

Eigen::Vector2d face_uv(const Box& box, int face, const Eigen::Vector3d& p) {
  const Eigen::Vector3d& h = box.half;
  switch (face / 2) {
    case 0: return {(p.y() + h.y()) * kTexelsPerMetre, (h.z() - p.z()) * kTexelsPerMetre};
    case 1: return {(p.x() + h.x()) * kTexelsPerMetre, (h.z() - p.z()) * kTexelsPerMetre};
    default: return {(p.x() + h.x()) * kTexelsPerMetre, (p.y() + h.y()) * kTexelsPerMetre};
  }
}

}  // namespace crowdslam::synth
