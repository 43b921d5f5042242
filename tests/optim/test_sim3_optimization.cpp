#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "crowdslam/optim/sim3_optimization.h"
#include "synthetic.h"
#include "test_support.h"

using namespace crowdslam::optim;
using namespace crowdslam::optim::test;
using crowdslam::geometry::Sim3;
using crowdslam::geometry::Sim3Match;

namespace {

struct MatchScene {
  Sim3 cam1_from_cam2;
  std::vector<Sim3Match> matches;
  std::vector<bool> injected_outlier;
};

// Points seen by both cameras (depth 1-6 m in camera 1); pixels with Gaussian noise of 1.2^level px;
// a share of the matches gets pixel1 (or pixel2) moved 20-50 px.
MatchScene make_match_scene(const Sim3& cam1_from_cam2, int num_matches, double outlier_ratio,
                            unsigned seed) {
  const PinholeCamera camera = test_camera();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, 3);
  const Sim3 cam2_from_cam1 = cam1_from_cam2.inverse();
  MatchScene scene;
  scene.cam1_from_cam2 = cam1_from_cam2;
  while (static_cast<int>(scene.matches.size()) < num_matches) {
    Sim3Match m;
    m.point_in_cam1 = random_visible_point(camera, SE3(), 1.0, 6.0, rng);
    m.point_in_cam2 = cam2_from_cam1 * m.point_in_cam1;
    if (m.point_in_cam2.z() < 0.1 || !camera.is_in_image(camera.project(m.point_in_cam2))) continue;
    const double sigma1 = std::pow(1.2, level(rng));
    const double sigma2 = std::pow(1.2, level(rng));
    m.sigma2_1 = sigma1 * sigma1;
    m.sigma2_2 = sigma2 * sigma2;
    m.pixel1 = camera.project(m.point_in_cam1) + sigma1 * Vec2(noise(rng), noise(rng));
    m.pixel2 = camera.project(m.point_in_cam2) + sigma2 * Vec2(noise(rng), noise(rng));
    const bool outlier = unit(rng) < outlier_ratio;
    if (outlier) {
      const double angle = 2.0 * M_PI * unit(rng);
      const Vec2 shift = (20.0 + 30.0 * unit(rng)) * Vec2(std::cos(angle), std::sin(angle));
      (unit(rng) < 0.5 ? m.pixel1 : m.pixel2) += shift;
    }
    scene.matches.push_back(m);
    scene.injected_outlier.push_back(outlier);
  }
  return scene;
}

double rotation_error_deg(const Sim3& a, const Sim3& b) {
  return crowdslam::geometry::rotation_angle(a.rotation_matrix().transpose() * b.rotation_matrix()) * 180.0 /
         M_PI;
}

Sim3 truth(double scale) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.3, Vec3(0.1, 1.0, -0.2).normalized()));
  return Sim3(q, Vec3(0.3, 0.05, -0.2), scale);
}

// Initial guess 3 deg and 8 cm (times the scale) off, scale off by 5 %.
Sim3 perturbed(const Sim3& s, double scale_factor) {
  const Eigen::Quaterniond dq(Eigen::AngleAxisd(3.0 * M_PI / 180.0, Vec3(1.0, -0.5, 0.3).normalized()));
  return Sim3(dq * s.rotation(), s.translation() + s.scale() * Vec3(0.05, -0.05, 0.04),
              s.scale() * scale_factor);
}

void expect_refines(const MatchScene& scene, const Sim3& initial, const Sim3OptimizationOptions& options) {
  const PinholeCamera camera = test_camera();
  std::vector<bool> use(scene.matches.size(), true);
  use[0] = false;  // an unused match is never an inlier
  const Sim3OptimizationResult result = optimize_sim3(camera, camera, scene.matches, use, initial, options);
  const double rotation_before = rotation_error_deg(initial, scene.cam1_from_cam2);
  const double rotation_after = rotation_error_deg(result.cam1_from_cam2, scene.cam1_from_cam2);
  const double translation_before = (initial.translation() - scene.cam1_from_cam2.translation()).norm();
  const double translation_after =
      (result.cam1_from_cam2.translation() - scene.cam1_from_cam2.translation()).norm();
  std::printf(
      "[ sim3 ] rotation %.3f -> %.4f deg, translation %.4f -> %.5f m, scale %.4f -> %.5f (truth %.2f), "
      "%d inliers\n",
      rotation_before, rotation_after, translation_before, translation_after, initial.scale(),
      result.cam1_from_cam2.scale(), scene.cam1_from_cam2.scale(), result.num_inliers);
  EXPECT_LT(rotation_after, 0.1);
  EXPECT_LT(translation_after, 0.005 * scene.cam1_from_cam2.scale());
  EXPECT_NEAR(result.cam1_from_cam2.scale(), scene.cam1_from_cam2.scale(),
              0.005 * scene.cam1_from_cam2.scale());
  ASSERT_EQ(result.inliers.size(), scene.matches.size());
  EXPECT_FALSE(result.inliers[0]);
  int true_inliers = 0;
  int kept_inliers = 0;
  int counted = 0;
  for (std::size_t i = 1; i < scene.matches.size(); ++i) {
    if (scene.injected_outlier[i]) {
      EXPECT_FALSE(result.inliers[i]) << "injected outlier " << i << " kept";
    } else {
      ++true_inliers;
      kept_inliers += result.inliers[i] ? 1 : 0;
    }
    counted += result.inliers[i] ? 1 : 0;
  }
  EXPECT_EQ(result.num_inliers, counted);
  // chi2 = 10 per 2-dof term: ~99.3 % of noisy inliers pass each of the two tests.
  EXPECT_GT(kept_inliers, 0.95 * true_inliers);
}

}  // namespace

TEST(Sim3Optimization, FixedScaleConvergesAndRejectsOutliers) {
  const MatchScene scene = make_match_scene(truth(1.0), 200, 0.15, 1);
  expect_refines(scene, perturbed(scene.cam1_from_cam2, 1.0), Sim3OptimizationOptions{});
}

TEST(Sim3Optimization, FreeScaleRecoversTheScale) {
  const MatchScene scene = make_match_scene(truth(1.6), 200, 0.15, 2);
  Sim3OptimizationOptions options;
  options.fix_scale = false;
  expect_refines(scene, perturbed(scene.cam1_from_cam2, 1.05), options);
}

TEST(Sim3Optimization, FixedScaleKeepsTheInitialScale) {
  const MatchScene scene = make_match_scene(truth(1.0), 100, 0.0, 3);
  const PinholeCamera camera = test_camera();
  const Sim3 initial = perturbed(scene.cam1_from_cam2, 1.1);
  const Sim3OptimizationResult result =
      optimize_sim3(camera, camera, scene.matches, std::vector<bool>(scene.matches.size(), true), initial);
  EXPECT_EQ(result.cam1_from_cam2.scale(), initial.scale());
}

TEST(Sim3Optimization, NothingUsedReturnsTheInitialGuess) {
  const MatchScene scene = make_match_scene(truth(1.0), 30, 0.0, 4);
  const PinholeCamera camera = test_camera();
  const Sim3 initial = perturbed(scene.cam1_from_cam2, 1.0);
  const Sim3OptimizationResult result =
      optimize_sim3(camera, camera, scene.matches, std::vector<bool>(scene.matches.size(), false), initial);
  EXPECT_EQ(result.num_inliers, 0);
  EXPECT_EQ(result.cam1_from_cam2.translation(), initial.translation());
}

TEST(Sim3Optimization, OptionsCheckNamesTheKey) {
  using crowdslam::test::error_of;
  Sim3OptimizationOptions options;
  EXPECT_EQ(error_of([&] { options.check(); }), "");
  options.chi2 = -1.0;
  EXPECT_NE(error_of([&] { options.check(); }).find("chi2"), std::string::npos);
  options = {};
  options.iterations_first = 0;
  EXPECT_NE(error_of([&] { options.check(); }).find("iterations_first"), std::string::npos);
  options = {};
  options.iterations_second = -1;
  EXPECT_NE(error_of([&] { options.check(); }).find("iterations_second"), std::string::npos);
}
