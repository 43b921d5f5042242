// The ground under a vehicle's camera (geometry/ground_plane.h): found among the other points a
// keyframe sees, the lane's road rather than the pavement beside it, and measured in each keyframe's own
// scale, so that a monocular map's scale drift shows as a change of height.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "crowdslam/geometry/ground_plane.h"
#include "crowdslam/util/error.h"

using namespace crowdslam;
using geometry::GroundPlaneOptions;
using geometry::Vec3;

namespace {

constexpr double kDegree = M_PI / 180.0;

// The ground's normal in a camera pitched down by `pitch_deg` (x right, y down, z forward).
Vec3 pitched_normal(double pitch_deg) {
  return Vec3(0.0, std::cos(pitch_deg * kDegree), -std::sin(pitch_deg * kDegree));
}

// `count` camera-frame points on the plane normal . p = height, x in [x0, x1] (sideways) and z in
// [z0, z1] (ahead), with Gaussian noise along the normal.
void add_plane_points(std::vector<Vec3>& points, const Vec3& normal, double height, double x0, double x1, double z0,
                      double z1, int count, double noise, std::mt19937& rng) {
  std::uniform_real_distribution<double> ux(x0, x1);
  std::uniform_real_distribution<double> uz(z0, z1);
  std::normal_distribution<double> n(0.0, noise);
  for (int i = 0; i < count; ++i) {
    const double x = ux(rng);
    const double z = uz(rng);
    // y from normal . (x, y, z) = height + noise
    const double y = (height + n(rng) - normal.x() * x - normal.z() * z) / normal.y();
    points.emplace_back(x, y, z);
  }
}

// Clutter a street shows: house fronts on both sides and points above the horizon.
void add_clutter(std::vector<Vec3>& points, double height, int count, std::mt19937& rng) {
  std::uniform_real_distribution<double> side(0.0, 1.0);
  std::uniform_real_distribution<double> uy(-3.0 * height, 0.9 * height);
  std::uniform_real_distribution<double> uz(4.0, 40.0);
  for (int i = 0; i < count; ++i) {
    const double x = side(rng) < 0.5 ? -4.0 * height : 4.5 * height;
    points.emplace_back(x, uy(rng), uz(rng));
  }
}

double angle_deg(const Vec3& a, const Vec3& b) { return std::acos(std::min(1.0, a.normalized().dot(b.normalized()))) / kDegree; }

}  // namespace

TEST(GroundPlane, RansacFindsTheRoadAmongHouseFronts) {
  std::mt19937 rng(4);
  const Vec3 normal = pitched_normal(2.0);
  std::vector<Vec3> points;
  add_plane_points(points, normal, 1.65, -3.0, 3.0, 6.0, 30.0, 60, 0.01, rng);
  add_clutter(points, 1.65, 200, rng);
  const auto plane = geometry::fit_ground_plane(points, GroundPlaneOptions{}, 1);
  ASSERT_TRUE(plane.has_value());
  EXPECT_LT(angle_deg(plane->normal, normal), 0.3);
  EXPECT_NEAR(plane->distance, 1.65, 0.02);
  EXPECT_GE(plane->inliers.size(), 55u);
  EXPECT_LE(plane->inliers.size(), 70u);  // the road's 60, and hardly any house point
}

TEST(GroundPlane, NoPlaneWithoutEnoughPointsBelowTheHorizon) {
  std::mt19937 rng(5);
  std::vector<Vec3> points;
  add_plane_points(points, Vec3::UnitY(), 1.65, -3.0, 3.0, 6.0, 30.0, 10, 0.01, rng);  // 10 < min_inliers 15
  for (int i = 0; i < 100; ++i) points.emplace_back(0.1 * i, -1.0, 10.0);                // above the horizon
  EXPECT_FALSE(geometry::fit_ground_plane(points, GroundPlaneOptions{}, 1).has_value());
  EXPECT_FALSE(geometry::ground_along_normal(points, Vec3::UnitY(), GroundPlaneOptions{}).has_value());
}

TEST(GroundPlane, AlongTheNormalTheLaneWinsOverAWiderPavement) {
  // A pavement 15 cm above the road with twice the road's points: the most common height overall, but
  // beside the lane. The ground under the car is the road's.
  std::mt19937 rng(6);
  const Vec3 normal = Vec3::UnitY();
  std::vector<Vec3> points;
  add_plane_points(points, normal, 1.65, -2.0, 2.0, 6.0, 25.0, 30, 0.005, rng);  // the lane
  add_plane_points(points, normal, 1.50, 3.5, 8.0, 6.0, 25.0, 60, 0.005, rng);   // the pavement
  const auto plane = geometry::ground_along_normal(points, normal, GroundPlaneOptions{});
  ASSERT_TRUE(plane.has_value());
  EXPECT_NEAR(plane->distance, 1.65, 0.01);
  EXPECT_EQ(plane->inliers.size(), 30u);
  for (std::size_t i : plane->inliers) EXPECT_LT(i, 30u);  // only the lane's points
  // Without the lateral limit (a very wide one) the pavement would have won.
  GroundPlaneOptions wide;
  wide.max_lateral_ratio = 100.0;
  const auto widest = geometry::ground_along_normal(points, normal, wide);
  ASSERT_TRUE(widest.has_value());
  EXPECT_NEAR(widest->distance, 1.50, 0.01);
}

TEST(GroundPlane, AlongTheNormalFollowsAChangeOfSlopeWithinTheLimit) {
  std::mt19937 rng(7);
  const Vec3 mount = Vec3::UnitY();
  const Vec3 uphill = pitched_normal(2.0);  // the road ahead climbs 2 degrees: within 5
  std::vector<Vec3> points;
  add_plane_points(points, uphill, 1.65, -2.0, 2.0, 6.0, 12.0, 60, 0.003, rng);
  const auto plane = geometry::ground_along_normal(points, mount, GroundPlaneOptions{});
  ASSERT_TRUE(plane.has_value());
  EXPECT_LT(angle_deg(plane->normal, uphill), 0.2);
  EXPECT_NEAR(plane->distance, 1.65, 0.01);
  EXPECT_EQ(plane->inliers.size(), 60u);
  // 8 degrees is beyond max_normal_change_deg: the mount's normal is kept.
  std::vector<Vec3> steep;
  add_plane_points(steep, pitched_normal(8.0), 1.65, -2.0, 2.0, 6.0, 6.4, 40, 0.001, rng);
  const auto kept = geometry::ground_along_normal(steep, mount, GroundPlaneOptions{});
  ASSERT_TRUE(kept.has_value());
  EXPECT_LT(angle_deg(kept->normal, mount), 1e-9);
}

TEST(GroundPlane, ConsensusNormalIgnoresTheFitsThatDisagree) {
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0.0, 0.3 * kDegree);
  const Vec3 truth = pitched_normal(1.5);
  std::vector<Vec3> normals;
  for (int i = 0; i < 12; ++i) {
    normals.push_back((truth + Vec3(n(rng), n(rng), n(rng))).normalized());
  }
  for (int i = 0; i < 5; ++i) normals.push_back(pitched_normal(12.0 + i));  // a kerb, a car's side
  const auto normal = geometry::consensus_normal(normals, 3.0, 4);
  ASSERT_TRUE(normal.has_value());
  EXPECT_LT(angle_deg(*normal, truth), 0.3);
  EXPECT_NEAR(normal->norm(), 1.0, 1e-12);
  EXPECT_FALSE(geometry::consensus_normal(normals, 3.0, 13).has_value());  // 12 agree, 13 asked
  EXPECT_FALSE(geometry::consensus_normal({}, 3.0, 1).has_value());
}

TEST(GroundPlane, EstimateMeasuresEachKeyframesHeightInItsOwnScale) {
  // 20 keyframes of a map whose scale drifts from 0.8 to 1.0 of its final one: each keyframe sees the road
  // at 1.65 m times its scale, beside a pavement and house fronts. One keyframe sees a wrong ground (a
  // parked lorry's floor, twice as far down).
  std::mt19937 rng(9);
  const Vec3 normal = pitched_normal(1.0);
  std::vector<std::vector<Vec3>> keyframes(20);
  std::vector<double> scale(20);
  for (int k = 0; k < 20; ++k) {
    scale[k] = 0.8 + 0.2 * k / 19.0;
    const double h = 1.65 * scale[k];
    add_plane_points(keyframes[k], normal, h, -1.2 * h, 1.2 * h, 4 * h, 15 * h, 40, 0.002 * h, rng);
    add_plane_points(keyframes[k], normal, 0.91 * h, 2.5 * h, 5 * h, 4 * h, 15 * h, 50, 0.002 * h, rng);
    add_clutter(keyframes[k], h, 150, rng);
  }
  keyframes[7].clear();
  add_plane_points(keyframes[7], normal, 3.3, -2.0, 2.0, 6.0, 25.0, 40, 0.002, rng);
  const auto ground = geometry::estimate_ground(keyframes, GroundPlaneOptions{});
  ASSERT_TRUE(ground.has_value());
  // Single RANSAC fits may bridge the lane and the pavement (a plane rolled by 1-2 degrees holds both
  // within 3 %): the mounting's normal is only the start; each keyframe's plane is refined on its lane.
  EXPECT_LT(angle_deg(ground->normal, normal), 2.0);
  ASSERT_EQ(ground->planes.size(), 20u);
  EXPECT_EQ(ground->keyframes_with_ground(), 19);
  EXPECT_FALSE(ground->planes[7].has_value());  // 3.3 is beyond max_height_change of the median
  for (int k = 0; k < 20; ++k) {
    if (k == 7) continue;
    ASSERT_TRUE(ground->planes[k].has_value()) << k;
    EXPECT_NEAR(ground->planes[k]->distance / (1.65 * scale[k]), 1.0, 0.01) << k;
    EXPECT_LT(angle_deg(ground->planes[k]->normal, normal), 0.3) << k;
  }
  // The reference is the median keyframe's height: 1.65 m at the median scale.
  EXPECT_NEAR(ground->height, 1.65 * 0.9, 0.03);
}

TEST(GroundPlane, NoEstimateWithoutAConsensus) {
  std::mt19937 rng(10);
  std::vector<std::vector<Vec3>> keyframes(2);  // two fits: fewer than the 3 a consensus needs
  for (auto& points : keyframes) add_plane_points(points, Vec3::UnitY(), 1.65, -2, 2, 6, 25, 40, 0.002, rng);
  EXPECT_FALSE(geometry::estimate_ground(keyframes, GroundPlaneOptions{}).has_value());
  EXPECT_FALSE(geometry::estimate_ground({}, GroundPlaneOptions{}).has_value());
}

TEST(GroundPlane, OptionsCheckNamesTheBadValue) {
  auto fails_with = [](GroundPlaneOptions o, const std::string& key) {
    try {
      o.check();
      ADD_FAILURE() << "expected an InputError for " << key;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  GroundPlaneOptions o;
  EXPECT_NO_THROW(o.check());
  o.keyframe_sigma = 0.0;
  fails_with(o, "keyframe_sigma");
  o = {};
  o.max_tilt_deg = 90.0;
  fails_with(o, "max_tilt_deg");
  o = {};
  o.min_inliers = 2;
  fails_with(o, "min_inliers");
  o = {};
  o.max_lateral_ratio = -1.0;
  fails_with(o, "max_lateral_ratio");
  o = {};
  o.consensus_deg = 0.0;
  fails_with(o, "consensus_deg");
}
