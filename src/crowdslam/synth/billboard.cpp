#include "crowdslam/synth/billboard.h"

#include <cmath>

namespace crowdslam::synth {

std::array<Eigen::Vector3d, 4> Billboard::corners() const {
  const Eigen::Vector3d half_across(0.5 * width_m * axis.x(), 0.5 * width_m * axis.y(), 0.0);
  const Eigen::Vector3d up(0.0, 0.0, height_m);
  return {foot - half_across, foot + half_across, foot - half_across + up, foot + half_across + up};
}

Billboard facing_billboard(const Eigen::Vector2d& position, const Eigen::Vector3d& camera_centre,
                           double height_m, double aspect) {
  Eigen::Vector2d to_camera = camera_centre.head<2>() - position;
  const double n = to_camera.norm();
  to_camera = n > 1e-9 ? Eigen::Vector2d(to_camera / n) : Eigen::Vector2d(1.0, 0.0);
  Billboard b;
  b.foot = {position.x(), position.y(), 0.0};
  // The camera looks along -to_camera; its right (image +u) is that direction crossed with world up.
  b.axis = {-to_camera.y(), to_camera.x()};
  b.height_m = height_m;
  b.width_m = height_m * aspect;
  return b;
}

std::optional<QuadHit> intersect_quad(const Billboard& b, const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& dir, double t_min) {
  const double nx = b.axis.y();
  const double ny = -b.axis.x();
  const double denominator = nx * dir.x() + ny * dir.y();
  if (std::abs(denominator) < 1e-12) return std::nullopt;
  const double t = (nx * (b.foot.x() - origin.x()) + ny * (b.foot.y() - origin.y())) / denominator;
  if (!(t > t_min)) return std::nullopt;
  const double px = origin.x() + t * dir.x() - b.foot.x();
  const double py = origin.y() + t * dir.y() - b.foot.y();
  const double pz = origin.z() + t * dir.z() - b.foot.z();
  const double across = (b.axis.x() * px + b.axis.y() * py) / b.width_m + 0.5;
  const double down = 1.0 - pz / b.height_m;
  if (across < 0.0 || across > 1.0 || down < 0.0 || down > 1.0) return std::nullopt;
  return QuadHit{t, across, down};
}

}  // namespace crowdslam::synth
