#pragma once
// Moving objects of the synthetic scene that are not people (issue 16's test bed): a crate sliding back
// and forth along the -y wall, a door swinging on a hinge in the +x wall, a cart that drives back and
// forth along the +y side turning as it goes, and a second door in the -x wall. Up to kMaxMovers, always
// in that order; their motion is periodic and fixed (no randomness), and they stay clear of the camera
// paths and of the static obstacles. People walk around the floor area each one sweeps.
#include <Eigen/Core>
#include <vector>

#include "crowdslam/synth/box.h"

namespace crowdslam::synth {

constexpr int kMaxMovers = 4;

enum class MoverKind { kSlide, kDoor, kCart };

struct Mover {
  int id = 0;  // 1-based
  MoverKind kind = MoverKind::kSlide;
  // The mover's box at time t (seconds since the first frame); faces without textures.
  [[nodiscard]] Box box_at(double t) const;
  // Floor rectangle (min, max) the mover covers at any time.
  [[nodiscard]] std::pair<Eigen::Vector2d, Eigen::Vector2d> footprint() const;

  // Parameters (metres, seconds, radians).
  Eigen::Vector3d half = Eigen::Vector3d::Constant(0.3);
  Eigen::Vector2d start = Eigen::Vector2d::Zero();  // slide/cart: one end of the path; door: the hinge
  Eigen::Vector2d end = Eigen::Vector2d::Zero();    // slide/cart: the other end
  double base_yaw = 0.0;   // door: the closed panel's direction from the hinge
  double swing = 0.0;      // door: opening angle (signed); cart: yaw change over the path
  double period_s = 4.0;   // one full back-and-forth
};

// The first `count` movers (0 <= count <= kMaxMovers).
std::vector<Mover> make_movers(int count);

const char* to_string(MoverKind kind);

}  // namespace crowdslam::synth
