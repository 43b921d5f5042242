#pragma once
// A person drawn from a photograph: a vertical quad standing on the floor, turned about the vertical axis
// to face a camera centre, textured with a person sprite (sprites.h). The renderer (render.h) alpha-tests
// the sprite: rays through transparent texels pass on to whatever is behind.
#include <Eigen/Core>
#include <array>
#include <optional>

namespace crowdslam::synth {

struct Billboard {
  Eigen::Vector3d foot = Eigen::Vector3d::Zero();  // middle of the bottom edge (on the floor: z = 0)
  Eigen::Vector2d axis{1.0, 0.0};  // unit horizontal direction of the sprite's rows, left to right as seen
  double width_m = 0.5;
  double height_m = 1.75;
  int sprite = -1;        // index into Scene::sprites()
  bool mirrored = false;  // the sprite's columns right to left
  int person_id = 0;

  // Unit horizontal normal towards the side the quad faces.
  Eigen::Vector3d normal() const { return {axis.y(), -axis.x(), 0.0}; }
  // World corners: index bit 0 = right edge, bit 1 = top edge.
  std::array<Eigen::Vector3d, 4> corners() const;
};

// A billboard for a person standing at `position` (floor) turned to face `camera_centre` (its normal
// horizontal and towards the camera), `height_m` tall and `height_m * aspect` wide.
Billboard facing_billboard(const Eigen::Vector2d& position, const Eigen::Vector3d& camera_centre,
                           double height_m, double aspect);

// Where a ray origin + t * dir meets the quad: t (> t_min) and the hit's position on the quad as fractions
// across (0 = left edge, 1 = right edge, before mirroring) and down (0 = top, 1 = feet). nullopt when the
// ray misses the quad or runs parallel to it. No alpha test (render.h does it).
struct QuadHit {
  double t = 0.0;
  double across = 0.0;
  double down = 0.0;
};
std::optional<QuadHit> intersect_quad(const Billboard& billboard, const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& dir, double t_min = 1e-6);

}  // namespace crowdslam::synth
