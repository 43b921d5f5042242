#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "crowdslam/geometry/sim3_solver.h"
#include "test_support.h"

using namespace crowdslam::geometry;

namespace {

PinholeCamera make_camera() {
  PinholeCamera camera;
  camera.fx = 525.0;
  camera.fy = 525.0;
  camera.cx = 319.5;
  camera.cy = 239.5;
  camera.width = 640;
  camera.height = 480;
  return camera;
}

struct Scene {
  Sim3 cam1_from_cam2;
  std::vector<Sim3Match> matches;
  std::vector<bool> is_inlier;
};

// A point seen in camera 1 at a random pixel, depth 1-6 m (times the scale of camera-1 units).
Vec3 random_point_in(const PinholeCamera& camera, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(20.0, camera.width - 20.0);
  std::uniform_real_distribution<double> v(20.0, camera.height - 20.0);
  std::uniform_real_distribution<double> depth(1.0, 6.0);
  return camera.unproject(Vec2(u(rng), v(rng)), depth(rng));
}

bool visible(const PinholeCamera& camera, const Vec3& p) {
  return p.z() > 0.1 && camera.is_in_image(camera.project(p));
}

// Inliers: one point seen by both cameras, exact pixels. Outliers: two unrelated points, each seen
// exactly by its own camera (a wrong descriptor match). Keypoint levels 0-3 (sigma 1.2^level).
Scene make_scene(const Sim3& cam1_from_cam2, int num_matches, double outlier_ratio, unsigned seed) {
  const PinholeCamera camera = make_camera();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, 3);
  const Sim3 cam2_from_cam1 = cam1_from_cam2.inverse();
  Scene scene;
  scene.cam1_from_cam2 = cam1_from_cam2;
  while (static_cast<int>(scene.matches.size()) < num_matches) {
    Sim3Match m;
    m.sigma2_1 = std::pow(1.44, level(rng));
    m.sigma2_2 = std::pow(1.44, level(rng));
    const bool inlier = unit(rng) >= outlier_ratio;
    m.point_in_cam1 = random_point_in(camera, rng);
    if (inlier) {
      m.point_in_cam2 = cam2_from_cam1 * m.point_in_cam1;
    } else {
      m.point_in_cam2 = cam2_from_cam1 * random_point_in(camera, rng);
    }
    if (!visible(camera, m.point_in_cam2)) continue;
    m.pixel1 = camera.project(m.point_in_cam1);
    m.pixel2 = camera.project(m.point_in_cam2);
    scene.matches.push_back(m);
    scene.is_inlier.push_back(inlier);
  }
  return scene;
}

Sim3 truth_transform(double scale) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.35, Vec3(0.2, 1.0, 0.1).normalized()));
  return Sim3(q, Vec3(0.4, -0.1, 0.25), scale);
}

double rotation_error_deg(const Sim3& a, const Sim3& b) {
  return rotation_angle(a.rotation_matrix().transpose() * b.rotation_matrix()) * 180.0 / M_PI;
}

void expect_recovers(const Scene& scene, const Sim3SolverOptions& options) {
  const PinholeCamera camera = make_camera();
  const std::optional<Sim3Result> result = solve_sim3_ransac(camera, camera, scene.matches, options);
  ASSERT_TRUE(result.has_value());
  EXPECT_LT(rotation_error_deg(result->cam1_from_cam2, scene.cam1_from_cam2), 0.1);
  EXPECT_LT((result->cam1_from_cam2.translation() - scene.cam1_from_cam2.translation()).norm(), 1e-3);
  EXPECT_NEAR(result->cam1_from_cam2.scale(), scene.cam1_from_cam2.scale(), 1e-6);
  ASSERT_EQ(result->inliers.size(), scene.matches.size());
  int expected_inliers = 0;
  for (std::size_t i = 0; i < scene.matches.size(); ++i) {
    EXPECT_EQ(result->inliers[i], scene.is_inlier[i]) << "match " << i;
    expected_inliers += scene.is_inlier[i] ? 1 : 0;
  }
  EXPECT_EQ(result->num_inliers, expected_inliers);
  // Adaptive stopping: ~65 % inliers need ~15 samples for p = 0.99, far below max_iterations.
  EXPECT_LT(result->iterations, 60);
}

}  // namespace

TEST(Sim3Solver, RecoversRigidTransformWithOutliers) {
  const Scene scene = make_scene(truth_transform(1.0), 120, 0.35, 1);
  expect_recovers(scene, Sim3SolverOptions{});
}

TEST(Sim3Solver, RecoversSimilarityWithFreeScale) {
  const Scene scene = make_scene(truth_transform(1.7), 120, 0.4, 2);
  Sim3SolverOptions options;
  options.fix_scale = false;
  expect_recovers(scene, options);
}

TEST(Sim3Solver, FixedScaleCannotExplainAScaledScene) {
  // Scale 1.7 between the cameras: with s fixed to 1 only points near the reference depth could fit.
  const Scene scene = make_scene(truth_transform(1.7), 120, 0.0, 3);
  const PinholeCamera camera = make_camera();
  const std::optional<Sim3Result> result =
      solve_sim3_ransac(camera, camera, scene.matches, Sim3SolverOptions{});
  if (result) {
    std::printf("fixed scale on a scaled scene: %d of 120 inliers\n", result->num_inliers);
    EXPECT_LT(result->num_inliers, 60);
  }
  Sim3SolverOptions free_scale;
  free_scale.fix_scale = false;
  const std::optional<Sim3Result> free_result = solve_sim3_ransac(camera, camera, scene.matches, free_scale);
  ASSERT_TRUE(free_result.has_value());
  EXPECT_EQ(free_result->num_inliers, 120);
}

TEST(Sim3Solver, FailsOnPureOutliers) {
  const Scene scene = make_scene(truth_transform(1.0), 150, 1.0, 4);
  const PinholeCamera camera = make_camera();
  Sim3SolverOptions options;
  EXPECT_FALSE(solve_sim3_ransac(camera, camera, scene.matches, options).has_value());
  options.fix_scale = false;
  EXPECT_FALSE(solve_sim3_ransac(camera, camera, scene.matches, options).has_value());
}

TEST(Sim3Solver, FailsWithTooFewMatches) {
  const Scene scene = make_scene(truth_transform(1.0), 15, 0.0, 5);
  const PinholeCamera camera = make_camera();
  EXPECT_FALSE(solve_sim3_ransac(camera, camera, scene.matches, Sim3SolverOptions{}).has_value());
  Sim3SolverOptions options;
  options.min_inliers = 10;
  EXPECT_TRUE(solve_sim3_ransac(camera, camera, scene.matches, options).has_value());
  EXPECT_FALSE(solve_sim3_ransac(camera, camera, {scene.matches[0], scene.matches[1]}, options).has_value());
}

TEST(Sim3Solver, DeterministicForASeed) {
  // Noisy 3D points so that different samples give different models.
  Scene scene = make_scene(truth_transform(1.0), 100, 0.3, 6);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (Sim3Match& m : scene.matches) m.point_in_cam2 += Vec3(noise(rng), noise(rng), noise(rng));
  const PinholeCamera camera = make_camera();
  Sim3SolverOptions options;
  options.seed = 42;
  const auto a = solve_sim3_ransac(camera, camera, scene.matches, options);
  const auto b = solve_sim3_ransac(camera, camera, scene.matches, options);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->iterations, b->iterations);
  EXPECT_EQ(a->inliers, b->inliers);
  EXPECT_EQ(a->cam1_from_cam2.translation(), b->cam1_from_cam2.translation());
  EXPECT_EQ(a->cam1_from_cam2.rotation().coeffs(), b->cam1_from_cam2.rotation().coeffs());
  EXPECT_LT(rotation_error_deg(a->cam1_from_cam2, scene.cam1_from_cam2), 0.5);
}

TEST(Sim3Solver, OptionsCheckNamesTheKey) {
  using crowdslam::test::error_of;
  Sim3SolverOptions options;
  EXPECT_EQ(error_of([&] { options.check(); }), "");
  options.probability = 1.0;
  EXPECT_NE(error_of([&] { options.check(); }).find("probability"), std::string::npos);
  options = {};
  options.min_inliers = 2;
  EXPECT_NE(error_of([&] { options.check(); }).find("min_inliers"), std::string::npos);
  options = {};
  options.max_iterations = 0;
  EXPECT_NE(error_of([&] { options.check(); }).find("max_iterations"), std::string::npos);
  options = {};
  options.chi2 = 0.0;
  EXPECT_NE(error_of([&] { options.check(); }).find("chi2"), std::string::npos);
}
