#pragma once
// The one primitive of the synthetic scene: a textured box, upright (rotated only about the world z
// axis), seen from outside (obstacles, people) or from inside (the room).
#include <Eigen/Core>
#include <array>
#include <optional>

namespace crowdslam::synth {

// Texture mapping of one face: texture index into Scene::textures() and an offset in texels.
struct Face {
  int texture = -1;
  double shade = 1.0;  // Lambertian factor of this face under the scene's fixed light
  double u_offset = 0.0;
  double v_offset = 0.0;
};

struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5);  // half extents along the box's own axes
  double yaw = 0.0;     // rotation of the box axes about world z (radians)
  bool inside = false;  // true for the room: rays start inside and hit its far side
  int person_id = 0;    // 0 = static scene or a mover
  int mover_id = 0;     // 0 = static scene or a person (movers.h)
  // Faces in the order -x, +x, -y, +y, -z, +z of the box's own axes.
  std::array<Face, 6> faces{};

  static Box axis_aligned(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner);
  // World corners, bottom four first.
  std::array<Eigen::Vector3d, 8> corners() const;
  // World point -> box frame and world direction -> box frame.
  Eigen::Vector3d to_local(const Eigen::Vector3d& world_point) const;
  Eigen::Vector3d dir_to_local(const Eigen::Vector3d& world_dir) const;
  // Outward normal of a face in world coordinates (inward for an `inside` box).
  Eigen::Vector3d face_normal(int face) const;
};

struct BoxHit {
  double t = 0.0;  // ray parameter: hit = origin + t * dir
  int face = 0;
};

// Ray-box intersection in the box's own frame (origin and dir already transformed with to_local /
// dir_to_local). Outside boxes: first hit in front (t > t_min); inside boxes: the exit point.
std::optional<BoxHit> intersect_local(const Box& box, const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& dir, double t_min = 1e-6);

// Texture coordinates (level-0 texels, before face offsets) of a local hit point on a face.
Eigen::Vector2d face_uv(const Box& box, int face, const Eigen::Vector3d& local_point);

}  // namespace crowdslam::synth
