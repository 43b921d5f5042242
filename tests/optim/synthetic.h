#pragma once
// Synthetic cameras, points and perturbations for the optim tests (header only).
#include <cmath>
#include <random>
#include <vector>

#include "crowdslam/geometry/camera.h"
#include "crowdslam/geometry/se3.h"
#include "crowdslam/optim/bundle_adjustment.h"
#include "crowdslam/optim/pose_optimizer.h"

namespace crowdslam::optim::test {

using geometry::PinholeCamera;
using geometry::SE3;
using geometry::Vec2;
using geometry::Vec3;
using geometry::Vec6;

inline PinholeCamera test_camera() {
  PinholeCamera camera;
  camera.fx = 525.0;
  camera.fy = 525.0;
  camera.cx = 319.5;
  camera.cy = 239.5;
  camera.width = 640;
  camera.height = 480;
  camera.bf = 40.0;  // RGB-D "virtual stereo" baseline 7.6 cm
  return camera;
}

inline Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 v(n(rng), n(rng), n(rng));
  return v.normalized();
}

// Pose moved by exactly `translation_m` and rotated by exactly `angle_rad` about random axes.
inline SE3 perturb(const SE3& pose, double translation_m, double angle_rad, std::mt19937& rng) {
  const Eigen::Quaterniond dq(Eigen::AngleAxisd(angle_rad, random_unit(rng)));
  return SE3(dq * pose.rotation(), pose.translation() + translation_m * random_unit(rng));
}

// A world point seen by `cam_from_world` at a random pixel inside the image, depth in [near, far].
inline Vec3 random_visible_point(const PinholeCamera& camera, const SE3& cam_from_world, double near, double far,
                                 std::mt19937& rng) {
  std::uniform_real_distribution<double> u(10.0, camera.width - 10.0);
  std::uniform_real_distribution<double> v(10.0, camera.height - 10.0);
  std::uniform_real_distribution<double> depth(near, far);
  const Vec3 p_cam = camera.unproject(Vec2(u(rng), v(rng)), depth(rng));
  return cam_from_world.inverse() * p_cam;
}

inline double translation_error(const SE3& a, const SE3& b) {
  return (a.inverse().translation() - b.inverse().translation()).norm();
}
inline double rotation_error_rad(const SE3& a, const SE3& b) {
  return geometry::rotation_angle(a.rotation_matrix().transpose() * b.rotation_matrix());
}

inline SE3 random_pose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec6 twist;
  twist << u(rng), u(rng), u(rng), 0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng);
  return SE3::exp(twist);
}

// One camera observing random points (optionally stereo, with gross outliers), for pose optimisation.
struct PoseScene {
  SE3 truth;
  std::vector<PoseObservation> observations;
  std::vector<bool> is_outlier;
};

struct PoseSceneSpec {
  int num_points = 300;
  double pixel_noise = 1.0;
  double outlier_ratio = 0.0;
  double stereo_ratio = 0.0;
  int max_level = 3;  // levels 0..max_level, sigma = 1.2^level
  unsigned seed = 1;
};

inline PoseScene make_pose_scene(const PinholeCamera& camera, const PoseSceneSpec& spec) {
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, spec.max_level);
  PoseScene scene;
  scene.truth = random_pose(rng);
  for (int i = 0; i < spec.num_points; ++i) {
    const Vec3 world = random_visible_point(camera, scene.truth, 1.0, 8.0, rng);
    const Vec3 p_cam = scene.truth * world;
    const double level_sigma = std::pow(1.2, level(rng));  // ORB pyramid scale factor 1.2
    const double sigma = level_sigma * spec.pixel_noise;
    PoseObservation obs;
    obs.point_world = world;
    obs.inv_sigma2 = 1.0 / (level_sigma * level_sigma);
    obs.pixel = camera.project(p_cam) + sigma * Vec2(noise(rng), noise(rng));
    if (unit(rng) < spec.stereo_ratio) {
      obs.right_u = camera.right_u(camera.project(p_cam).x(), p_cam.z()) + sigma * noise(rng);
    }
    const bool outlier = unit(rng) < spec.outlier_ratio;
    if (outlier) {
      // Gross mismatch: 15-80 px away in a random direction.
      const double angle = 2.0 * M_PI * unit(rng);
      obs.pixel += (15.0 + 65.0 * unit(rng)) * Vec2(std::cos(angle), std::sin(angle));
      if (obs.is_stereo()) obs.right_u = obs.pixel.x() - camera.bf / p_cam.z();
    }
    scene.observations.push_back(obs);
    scene.is_outlier.push_back(outlier);
  }
  return scene;
}

// A local-BA problem: keyframes on a sideways track looking at a box of points.
struct BaScene {
  std::vector<BaKeyframe> truth_keyframes;
  std::vector<BaPoint> truth_points;
  std::vector<BaKeyframe> keyframes;  // perturbed (fixed ones exact)
  std::vector<BaPoint> points;        // perturbed
  std::vector<BaObservation> observations;
  std::vector<bool> injected_outlier;
};

struct BaSceneSpec {
  int num_keyframes = 10;
  int num_points = 500;
  int num_fixed = 2;
  double pixel_noise = 1.0;
  double stereo_ratio = 0.3;
  int num_outliers = 20;
  double pose_translation_noise = 0.03;
  double pose_rotation_noise = 1.0 * M_PI / 180.0;
  double point_noise = 0.05;
  unsigned seed = 1;
};

inline BaScene make_ba_scene(const PinholeCamera& camera, const BaSceneSpec& spec) {
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  BaScene scene;
  for (int k = 0; k < spec.num_keyframes; ++k) {
    const Vec3 center(0.15 * k, 0.03 * std::sin(k), 0.02 * k);
    const Eigen::Matrix3d world_from_cam =
        (Eigen::AngleAxisd(0.02 * k, Vec3::UnitY()) * Eigen::AngleAxisd(0.01 * k, Vec3::UnitX())).toRotationMatrix();
    scene.truth_keyframes.push_back({100 + k, SE3(world_from_cam, center).inverse(), k < spec.num_fixed});
  }
  for (int p = 0; p < spec.num_points; ++p) {
    const Vec3 world(-2.0 + 5.5 * unit(rng), -1.5 + 3.0 * unit(rng), 3.0 + 5.0 * unit(rng));
    scene.truth_points.push_back({1000 + p, world});
  }
  for (const BaPoint& point : scene.truth_points) {
    for (const BaKeyframe& keyframe : scene.truth_keyframes) {
      const Vec3 p_cam = keyframe.cam_from_world * point.world;
      if (p_cam.z() <= 0.1) continue;
      const Vec2 pixel = camera.project(p_cam);
      if (!camera.is_in_image(pixel)) continue;
      BaObservation obs;
      obs.keyframe_id = keyframe.id;
      obs.point_id = point.id;
      const double level_sigma = std::pow(1.2, static_cast<int>(unit(rng) * 4));
      obs.inv_sigma2 = 1.0 / (level_sigma * level_sigma);
      const double sigma = level_sigma * spec.pixel_noise;
      obs.pixel = pixel + sigma * Vec2(noise(rng), noise(rng));
      if (unit(rng) < spec.stereo_ratio) obs.right_u = camera.right_u(pixel.x(), p_cam.z()) + sigma * noise(rng);
      scene.observations.push_back(obs);
      scene.injected_outlier.push_back(false);
    }
  }
  // Gross outliers: 30-60 px off, spread over the observation list.
  std::uniform_int_distribution<std::size_t> pick(0, scene.observations.size() - 1);
  for (int n = 0; n < spec.num_outliers;) {
    const std::size_t i = pick(rng);
    if (scene.injected_outlier[i]) continue;
    const double angle = 2.0 * M_PI * unit(rng);
    const Vec2 shift = (30.0 + 30.0 * unit(rng)) * Vec2(std::cos(angle), std::sin(angle));
    scene.observations[i].pixel += shift;
    if (scene.observations[i].is_stereo()) scene.observations[i].right_u += shift.x();
    scene.injected_outlier[i] = true;
    ++n;
  }
  scene.keyframes = scene.truth_keyframes;
  for (BaKeyframe& keyframe : scene.keyframes) {
    if (!keyframe.fixed) {
      keyframe.cam_from_world = perturb(keyframe.cam_from_world, spec.pose_translation_noise,
                                        spec.pose_rotation_noise, rng);
    }
  }
  scene.points = scene.truth_points;
  for (BaPoint& point : scene.points) point.world += spec.point_noise * Vec3(noise(rng), noise(rng), noise(rng));
  return scene;
}

}  // namespace crowdslam::optim::test
