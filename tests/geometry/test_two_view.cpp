// Two-view geometry (monocular initialisation): model estimation, selection and reconstruction against
// synthetic correspondences with known H, F and relative pose.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include "crowdslam/geometry/two_view.h"
#include "crowdslam/util/error.h"

using namespace crowdslam::geometry;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

PinholeCamera test_camera() {
  PinholeCamera camera;
  camera.fx = 525.0;
  camera.fy = 525.0;
  camera.cx = 319.5;
  camera.cy = 239.5;
  camera.width = 640;
  camera.height = 480;
  return camera;
}

SE3 relative_pose(double yaw_deg, double pitch_deg, const Vec3& translation) {
  const Mat3 r =
      (Eigen::AngleAxisd(yaw_deg * kDeg, Vec3::UnitY()) * Eigen::AngleAxisd(pitch_deg * kDeg, Vec3::UnitX()))
          .toRotationMatrix();
  return SE3(r, translation);
}

struct Correspondences {
  std::vector<Vec2> points1;
  std::vector<Vec2> points2;
  std::vector<bool> is_outlier;
  std::vector<Vec3> truth;  // the point in camera 1 (zero for outliers)
};

// Points in camera 1's frame seen by both cameras, with Gaussian pixel noise, plus `outliers` random pairs.
Correspondences make_correspondences(const std::vector<Vec3>& points_cam1, const SE3& cam2_from_cam1,
                                     double noise_px, int outliers, std::uint64_t seed) {
  const PinholeCamera camera = test_camera();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_px);
  std::uniform_real_distribution<double> u(0.0, 640.0);
  std::uniform_real_distribution<double> v(0.0, 480.0);
  Correspondences c;
  for (const auto& p : points_cam1) {
    const Vec3 q = cam2_from_cam1 * p;
    if (p.z() <= 0 || q.z() <= 0) continue;
    const Vec2 x1 = camera.project(p);
    const Vec2 x2 = camera.project(q);
    if (!camera.is_in_image(x1) || !camera.is_in_image(x2)) continue;
    c.points1.push_back(x1 + (noise_px > 0 ? Vec2(noise(rng), noise(rng)) : Vec2::Zero()));
    c.points2.push_back(x2 + (noise_px > 0 ? Vec2(noise(rng), noise(rng)) : Vec2::Zero()));
    c.is_outlier.push_back(false);
    c.truth.push_back(p);
  }
  for (int i = 0; i < outliers; ++i) {
    c.points1.emplace_back(u(rng), v(rng));
    c.points2.emplace_back(u(rng), v(rng));
    c.is_outlier.push_back(true);
    c.truth.push_back(Vec3::Zero());
  }
  // Shuffle so that outliers are not all at the end.
  std::vector<size_t> order(c.points1.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  Correspondences shuffled;
  for (size_t i : order) {
    shuffled.points1.push_back(c.points1[i]);
    shuffled.points2.push_back(c.points2[i]);
    shuffled.is_outlier.push_back(c.is_outlier[i]);
    shuffled.truth.push_back(c.truth[i]);
  }
  return shuffled;
}

// A general 3D scene: points spread over depths 2..8 m.
std::vector<Vec3> scene_points(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> xy(-3.0, 3.0);
  std::uniform_real_distribution<double> z(2.0, 8.0);
  std::vector<Vec3> points;
  for (int i = 0; i < n; ++i) points.emplace_back(xy(rng), xy(rng) * 0.75, z(rng));
  return points;
}

// Points on the plane n . X = d (camera 1 frame).
std::vector<Vec3> plane_points(int n, const Vec3& normal, double d, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uv(-0.6, 0.6);
  std::vector<Vec3> points;
  for (int i = 0; i < n; ++i) {
    const Vec3 ray(uv(rng), uv(rng) * 0.75, 1.0);
    const double depth = d / normal.dot(ray);
    if (depth > 0) points.push_back(depth * ray);
  }
  return points;
}

Mat3 true_fundamental(const SE3& cam2_from_cam1) {
  const Mat3 k_inv = test_camera().intrinsic_matrix().inverse();
  return k_inv.transpose() * skew(cam2_from_cam1.translation()) * cam2_from_cam1.rotation_matrix() * k_inv;
}

Mat3 true_homography(const SE3& cam2_from_cam1, const Vec3& normal, double d) {
  const Mat3 k = test_camera().intrinsic_matrix();
  const Mat3 h = cam2_from_cam1.rotation_matrix() + cam2_from_cam1.translation() * normal.transpose() / d;
  return k * h * k.inverse();
}

// Difference of two matrices defined up to scale and sign.
double projective_difference(const Mat3& a, const Mat3& b) {
  const Mat3 an = a / a.norm();
  const Mat3 bn = b / b.norm();
  return std::min((an - bn).norm(), (an + bn).norm());
}

double rotation_error_deg(const SE3& a, const SE3& b) {
  return rotation_angle(a.rotation_matrix().transpose() * b.rotation_matrix()) / kDeg;
}

double direction_error_deg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) / kDeg;
}

}  // namespace

TEST(TwoView, DltAndEightPointAreExactOnMinimalNoiseFreeSets) {
  const SE3 pose = relative_pose(4.0, -2.0, Vec3(0.4, 0.05, 0.1));
  const Vec3 normal = Vec3(0.1, -0.2, 1.0).normalized();
  auto plane = make_correspondences(plane_points(20, normal, 3.0, 1), pose, 0.0, 0, 2);
  ASSERT_GE(plane.points1.size(), 8u);
  plane.points1.resize(8);
  plane.points2.resize(8);
  EXPECT_LT(
      projective_difference(homography_dlt(plane.points1, plane.points2), true_homography(pose, normal, 3.0)),
      1e-8);
  auto scene = make_correspondences(scene_points(20, 3), pose, 0.0, 0, 4);
  ASSERT_GE(scene.points1.size(), 8u);
  scene.points1.resize(8);
  scene.points2.resize(8);
  const Mat3 f = fundamental_eight_point(scene.points1, scene.points2);
  EXPECT_LT(projective_difference(f, true_fundamental(pose)), 1e-6);
  EXPECT_NEAR(Eigen::JacobiSVD<Mat3>(f).singularValues()(2), 0.0, 1e-12);  // rank 2
}

TEST(TwoView, RansacRecoversHomographyDespiteOutliers) {
  const SE3 pose = relative_pose(3.0, 1.0, Vec3(0.3, -0.05, 0.05));
  const Vec3 normal = Vec3(0.0, -0.3, 1.0).normalized();
  const auto c = make_correspondences(plane_points(300, normal, 4.0, 5), pose, 0.0, 90, 6);
  const auto models = estimate_two_view_models(c.points1, c.points2, TwoViewOptions{});
  EXPECT_LT(projective_difference(models.homography_21, true_homography(pose, normal, 4.0)), 1e-6);
  int wrong = 0;
  for (size_t i = 0; i < c.is_outlier.size(); ++i) wrong += models.homography.inliers[i] == c.is_outlier[i];
  EXPECT_LE(wrong, 2);  // a random pair can fall within 2.4 px of the true transfer by chance
  EXPECT_EQ(models.selected, TwoViewModel::kHomography);
  EXPECT_GT(models.homography_ratio, 0.45);
}

TEST(TwoView, RansacRecoversFundamentalDespiteOutliers) {
  const SE3 pose = relative_pose(-5.0, 2.0, Vec3(-0.5, 0.1, 0.2));
  const auto c = make_correspondences(scene_points(400, 7), pose, 0.0, 100, 8);
  const auto models = estimate_two_view_models(c.points1, c.points2, TwoViewOptions{});
  EXPECT_LT(projective_difference(models.fundamental_21, true_fundamental(pose)), 1e-6);
  int inlier_outliers = 0;
  int missed_inliers = 0;
  for (size_t i = 0; i < c.is_outlier.size(); ++i) {
    if (c.is_outlier[i] && models.fundamental.inliers[i]) ++inlier_outliers;
    if (!c.is_outlier[i] && !models.fundamental.inliers[i]) ++missed_inliers;
  }
  EXPECT_EQ(missed_inliers, 0);
  EXPECT_LE(inlier_outliers, 10);  // within 2 px of an epipolar line by chance: a few percent of 100
  EXPECT_EQ(models.selected, TwoViewModel::kFundamental);
  EXPECT_LT(models.homography_ratio, 0.45);
}

TEST(TwoView, EssentialAndHomographyDecompositionsContainTheTruePose) {
  const SE3 pose = relative_pose(6.0, -3.0, Vec3(0.3, 0.1, -0.2));
  const Vec3 t_unit = pose.translation().normalized();
  const Mat3 k = test_camera().intrinsic_matrix();
  const Mat3 essential = k.transpose() * true_fundamental(pose) * k;
  const auto from_e = poses_from_essential(essential);
  ASSERT_EQ(from_e.size(), 4u);
  int found = 0;
  for (const auto& p : from_e)
    found += rotation_error_deg(p, pose) < 1e-4 && (p.translation() - t_unit).norm() < 1e-6;
  EXPECT_EQ(found, 1);
  const Vec3 normal = Vec3(0.2, 0.1, 1.0).normalized();
  const auto from_h = poses_from_homography(true_homography(pose, normal, 2.5), k);
  ASSERT_GE(from_h.size(), 2u);
  found = 0;
  for (const auto& p : from_h)
    found += rotation_error_deg(p, pose) < 1e-4 && (p.translation() - t_unit).norm() < 1e-6;
  EXPECT_EQ(found, 1);
}

TEST(TwoView, ReconstructsGeneralSceneWithNoiseAndOutliers) {
  const SE3 pose = relative_pose(4.0, 1.5, Vec3(0.35, -0.05, 0.1));
  const auto c = make_correspondences(scene_points(500, 11), pose, 0.7, 60, 12);
  TwoViewModels models;
  const auto r = reconstruct_two_view(test_camera(), c.points1, c.points2, TwoViewOptions{}, &models);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->model, TwoViewModel::kFundamental);
  EXPECT_LT(rotation_error_deg(r->cam2_from_cam1, pose), 0.5);
  EXPECT_LT(direction_error_deg(r->cam2_from_cam1.translation(), pose.translation()), 2.0);
  EXPECT_NEAR(r->cam2_from_cam1.translation().norm(), 1.0, 1e-9);
  EXPECT_GT(r->parallax_deg, 1.0);
  // Triangulated points: the true ones scaled by 1 / |t| (scale-free), no outlier among them.
  const double scale = 1.0 / pose.translation().norm();
  int checked = 0;
  for (size_t i = 0; i < c.points1.size(); ++i) {
    if (!r->triangulated[i]) continue;
    EXPECT_FALSE(c.is_outlier[i]);
    ++checked;
  }
  EXPECT_GT(checked, 300);
  // The triangulated points, brought to the true scale, match the true ones (median relative error; a
  // disparity of 25..100 px with 0.7 px noise and a residual rotation error of ~0.2 deg give a few %).
  std::vector<double> errors;
  for (size_t i = 0; i < c.points1.size(); ++i) {
    if (r->triangulated[i])
      errors.push_back((r->points_cam1[i] / scale - c.truth[i]).norm() / c.truth[i].norm());
  }
  std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.08);
}

TEST(TwoView, ReconstructsPlanarSceneThroughHomography) {
  // Sideways motion in front of a tilted plane: the twin solution of the homography puts part of the
  // plane behind a camera, so there is a clear winner (with forward motion both can be valid).
  const SE3 pose = relative_pose(-3.0, 2.0, Vec3(-0.4, 0.1, 0.0));
  const Vec3 normal = Vec3(0.0, -0.5, 1.0).normalized();
  const auto c = make_correspondences(plane_points(400, normal, 3.0, 13), pose, 0.5, 40, 14);
  const auto r = reconstruct_two_view(test_camera(), c.points1, c.points2, TwoViewOptions{});
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->model, TwoViewModel::kHomography);
  EXPECT_LT(rotation_error_deg(r->cam2_from_cam1, pose), 0.5);
  EXPECT_LT(direction_error_deg(r->cam2_from_cam1.translation(), pose.translation()), 2.0);
}

// A wall seen while the camera turns and moves sideways and back (a monocular camera re-anchoring where
// people left only a wall in view): the homography's two decompositions both put every point in front of
// both cameras, so without a prior the pair is ambiguous; a motion model's prediction tells them apart.
TEST(TwoView, APlanesTwoFoldAmbiguityIsResolvedByAMotionPrior) {
  const SE3 pose = relative_pose(12.0, 1.0, Vec3(-0.25, -0.01, 0.12));
  const Vec3 normal = Vec3(0.05, 0.0, 1.0).normalized();
  const auto c = make_correspondences(plane_points(400, normal, 3.0, 21), pose, 0.5, 20, 22);
  TwoViewModels models;
  EXPECT_FALSE(
      reconstruct_two_view(test_camera(), c.points1, c.points2, TwoViewOptions{}, &models).has_value());
  ASSERT_EQ(models.selected, TwoViewModel::kHomography);
  // The twin: the other decomposition with every point good (it differs from the truth).
  std::optional<SE3> twin;
  for (const auto& p : poses_from_homography(models.homography_21, test_camera().intrinsic_matrix())) {
    const auto check = check_relative_pose(p, test_camera(), c.points1, c.points2, models.homography.inliers, 1.0);
    if (check.num_good > 0.9 * models.homography.num_inliers && rotation_error_deg(p, pose) > 1.0) twin = p;
  }
  ASSERT_TRUE(twin.has_value());
  // A motion model's prediction: 3 degrees and 20 degrees of travel direction off the truth, metric.
  TwoViewPrior prior;
  prior.cam2_from_cam1 = SE3(relative_pose(15.0, 0.0, Vec3::Zero()).rotation(),
                             Eigen::AngleAxisd(20.0 * kDeg, Vec3::UnitY()) * pose.translation() * 0.1);
  const auto r = reconstruct_two_view(test_camera(), c.points1, c.points2, TwoViewOptions{}, nullptr, &prior);
  ASSERT_TRUE(r.has_value());
  EXPECT_LT(rotation_error_deg(r->cam2_from_cam1, pose), 0.5);
  EXPECT_LT(direction_error_deg(r->cam2_from_cam1.translation(), pose.translation()), 2.0);
  // A prior near the twin gives the twin: the prior chooses, the points cannot.
  prior.cam2_from_cam1 = *twin;
  const auto t = reconstruct_two_view(test_camera(), c.points1, c.points2, TwoViewOptions{}, nullptr, &prior);
  ASSERT_TRUE(t.has_value());
  EXPECT_LT(rotation_error_deg(t->cam2_from_cam1, *twin), 0.5);
  // A prior that agrees with neither (turning the other way, travelling the other way): nothing.
  prior.cam2_from_cam1 = SE3(relative_pose(-12.0, 0.0, Vec3::Zero()).rotation(), -pose.translation());
  EXPECT_FALSE(
      reconstruct_two_view(test_camera(), c.points1, c.points2, TwoViewOptions{}, nullptr, &prior).has_value());
  // Without a travel direction to check, the rotation alone decides, where it can.
  prior.cam2_from_cam1 = pose;
  prior.check_direction = false;
  EXPECT_TRUE(agrees_with_prior(pose, prior));
  EXPECT_FALSE(agrees_with_prior(relative_pose(30.0, 0.0, pose.translation()), prior));
}

TEST(TwoView, RejectsPureRotationAndTinyBaseline) {
  const auto points = scene_points(500, 15);
  // Pure rotation: a homography explains everything, and no hypothesis has parallax.
  const SE3 rotation = relative_pose(5.0, 2.0, Vec3::Zero());
  const auto c = make_correspondences(points, rotation, 0.5, 30, 16);
  TwoViewModels models;
  EXPECT_FALSE(
      reconstruct_two_view(test_camera(), c.points1, c.points2, TwoViewOptions{}, &models).has_value());
  EXPECT_EQ(models.selected, TwoViewModel::kHomography);
  // A 2 cm baseline at 2..8 m: parallax of the 50th-best point well below 1 degree.
  const SE3 tiny = relative_pose(2.0, 0.0, Vec3(0.02, 0.0, 0.0));
  const auto d = make_correspondences(points, tiny, 0.5, 30, 17);
  EXPECT_FALSE(reconstruct_two_view(test_camera(), d.points1, d.points2, TwoViewOptions{}).has_value());
  // Too few correspondences for RANSAC.
  std::vector<Vec2> few(7, Vec2(1, 1));
  EXPECT_FALSE(reconstruct_two_view(test_camera(), few, few, TwoViewOptions{}).has_value());
}

TEST(TwoView, OptionsCheckNamesTheBadValue) {
  TwoViewOptions options;
  EXPECT_NO_THROW(options.check());
  options.sigma_px = 0;
  EXPECT_THROW(options.check(), crowdslam::InputError);
  options = {};
  options.homography_ratio_threshold = 1.5;
  try {
    options.check();
    FAIL();
  } catch (const crowdslam::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("homography_ratio_threshold"), std::string::npos);
  }
}
