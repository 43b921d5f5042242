// Plane constraints in bundle adjustment (optim::BaPlaneConstraint): the camera's height above the ground
// sets a scale that the images alone cannot see, in both solvers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "crowdslam/optim/bundle_adjustment.h"
#include "synthetic.h"

using namespace crowdslam::optim;
using namespace crowdslam::optim::test;

namespace {

constexpr double kHeight = 1.65;  // the camera above the road (y down)

// Two stretches of road, 20 m apart, that share no point: four keyframes each (level cameras looking
// along +z), each stretch with road points and house fronts ahead of it. Observations are exact. The
// second stretch starts at 0.8 of the true scale (keyframes and points scaled about its first camera),
// which its images cannot tell: only the ground can.
struct TwoStretches {
  std::vector<BaKeyframe> keyframes;
  std::vector<BaPoint> points;
  std::vector<BaObservation> observations;
  std::vector<bool> on_ground;  // per point
  std::vector<int> stretch;     // per point: 0 or 1
};

TwoStretches make_two_stretches(const PinholeCamera& camera) {
  TwoStretches s;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> lateral(-2.0, 2.0);
  std::uniform_real_distribution<double> ahead(8.0, 20.0);
  std::uniform_real_distribution<double> up(-3.0, 1.0);
  std::uniform_real_distribution<double> side(0.0, 1.0);
  const double scale[2] = {1.0, 0.8};
  for (int g = 0; g < 2; ++g) {
    const Vec3 origin(0.0, 0.0, 20.0 * g);
    auto scaled = [&](const Vec3& x) { return Vec3(origin + scale[g] * (x - origin)); };
    std::vector<int> kf_ids;
    std::vector<SE3> truth_poses;
    for (int k = 0; k < 4; ++k) {
      const Vec3 centre = origin + Vec3(0.0, 0.0, k);
      truth_poses.emplace_back(Eigen::Quaterniond::Identity(), -centre);
      const int id = static_cast<int>(s.keyframes.size());
      kf_ids.push_back(id);
      s.keyframes.push_back({id, SE3(Eigen::Quaterniond::Identity(), -scaled(centre)), id == 0});
    }
    for (int i = 0; i < 160; ++i) {
      const bool ground = i < 60;
      const Vec3 x = ground ? origin + Vec3(lateral(rng), kHeight, ahead(rng))
                            : origin + Vec3(side(rng) < 0.5 ? -5.0 : 5.0, up(rng), ahead(rng));
      const int id = static_cast<int>(s.points.size());
      s.points.push_back({id, scaled(x)});
      s.on_ground.push_back(ground);
      s.stretch.push_back(g);
      for (int k = 0; k < 4; ++k) {
        const Vec3 p_cam = truth_poses[k] * x;
        const Vec2 pixel = camera.project(p_cam);
        if (p_cam.z() <= 0 || pixel.x() < 0 || pixel.y() < 0 || pixel.x() >= camera.width || pixel.y() >= camera.height)
          continue;
        BaObservation o;
        o.keyframe_id = kf_ids[k];
        o.point_id = id;
        o.pixel = pixel;
        o.inv_sigma2 = 1.0;
        s.observations.push_back(o);
      }
    }
  }
  return s;
}

// Each keyframe's ground points, held at kHeight with a keyframe sigma of 1 %.
std::vector<BaPlaneConstraint> ground_constraints(const TwoStretches& s) {
  std::vector<std::vector<int>> ground_of(s.keyframes.size());
  for (const auto& o : s.observations) {
    if (s.on_ground[o.point_id]) ground_of[o.keyframe_id].push_back(o.point_id);
  }
  std::vector<BaPlaneConstraint> planes;
  for (std::size_t k = 0; k < ground_of.size(); ++k) {
    const double sigma = 0.01 * std::sqrt(static_cast<double>(ground_of[k].size())) * kHeight;
    for (int p : ground_of[k]) planes.push_back({static_cast<int>(k), p, Vec3::UnitY(), kHeight, sigma});
  }
  return planes;
}

// The height of the camera of keyframe `k` above its stretch's road points, from the solution.
double camera_height(const TwoStretches& s, const BundleAdjustmentResult& r, int k) {
  const int g = k < 4 ? 0 : 1;
  double sum = 0.0;
  int n = 0;
  for (std::size_t p = 0; p < s.points.size(); ++p) {
    if (!s.on_ground[p] || s.stretch[p] != g) continue;
    sum += (r.keyframes[k].cam_from_world * r.points[p].world).y();
    ++n;
  }
  return sum / n;
}

double reprojection_rms_px(const PinholeCamera& camera, const TwoStretches& s, const BundleAdjustmentResult& r) {
  double sum = 0.0;
  for (const auto& o : s.observations) {
    sum += (camera.project(r.keyframes[o.keyframe_id].cam_from_world * r.points[o.point_id].world) - o.pixel).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(s.observations.size()));
}

}  // namespace

TEST(BundleAdjustmentGround, TheGroundSetsAScaleTheImagesCannotSee) {
  const PinholeCamera camera = test_camera();
  const TwoStretches s = make_two_stretches(camera);
  ASSERT_GT(s.observations.size(), 800u);
  for (const BaLinearSolver solver : {BaLinearSolver::kOwnSchur, BaLinearSolver::kSparseSchur}) {
    SCOPED_TRACE(solver == BaLinearSolver::kOwnSchur ? "own Schur" : "Ceres");
    BundleAdjustmentOptions options;
    options.linear_solver = solver;
    options.first_pass_iterations = 20;
    // Without the ground: every observation is already exact, so the second stretch keeps its 0.8.
    const auto plain = local_bundle_adjustment(camera, s.keyframes, s.points, s.observations, options);
    ASSERT_FALSE(plain.aborted);
    for (int k = 4; k < 8; ++k) EXPECT_NEAR(camera_height(s, plain, k), 0.8 * kHeight, 0.005) << k;
    // With it: the second stretch is rescaled to the first's, and the images are still explained.
    const auto held = local_bundle_adjustment(camera, s.keyframes, s.points, s.observations, options, nullptr,
                                              ground_constraints(s));
    ASSERT_FALSE(held.aborted);
    for (int k = 0; k < 8; ++k) EXPECT_NEAR(camera_height(s, held, k), kHeight, 0.01 * kHeight) << k;
    EXPECT_LT(reprojection_rms_px(camera, s, held), 0.05);
    EXPECT_TRUE(held.outliers.empty());
    // The 20 m between the stretches' first cameras, which the scaled start had at 20 m as well (it
    // scaled about that camera), and the second stretch's 3 m of driving, which it had at 2.4 m.
    const Vec3 c4 = held.keyframes[4].cam_from_world.inverse().translation();
    const Vec3 c7 = held.keyframes[7].cam_from_world.inverse().translation();
    EXPECT_NEAR((c7 - c4).norm(), 3.0, 0.03);
  }
}

TEST(BundleAdjustmentGround, ConstraintsOnUnknownIdsAreSkipped) {
  const PinholeCamera camera = test_camera();
  const TwoStretches s = make_two_stretches(camera);
  BundleAdjustmentOptions options;
  options.first_pass_iterations = 3;
  options.second_pass_iterations = 0;
  const std::vector<BaPlaneConstraint> unknown = {{99, 0, Vec3::UnitY(), kHeight, 0.1}, {0, 9999, Vec3::UnitY(), kHeight, 0.1}};
  const auto with = local_bundle_adjustment(camera, s.keyframes, s.points, s.observations, options, nullptr, unknown);
  const auto without = local_bundle_adjustment(camera, s.keyframes, s.points, s.observations, options);
  ASSERT_EQ(with.keyframes.size(), without.keyframes.size());
  for (std::size_t k = 0; k < with.keyframes.size(); ++k) {
    EXPECT_LT(translation_error(with.keyframes[k].cam_from_world, without.keyframes[k].cam_from_world), 1e-12);
  }
}
