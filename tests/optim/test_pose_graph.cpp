#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "crowdslam/optim/pose_graph.h"
#include "synthetic_loop.h"
#include "test_support.h"

using namespace crowdslam::optim;
using namespace crowdslam::optim::test;
using crowdslam::geometry::Sim3;
using crowdslam::geometry::Vec3;

namespace {

double rotation_error_deg(const Sim3& a, const Sim3& b) {
  return crowdslam::geometry::rotation_angle(a.rotation_matrix().transpose() * b.rotation_matrix()) * 180.0 /
         M_PI;
}

}  // namespace

TEST(PoseGraph, LoopEdgeRemovesAccumulatedDrift) {
  const LoopGraph graph = make_loop_graph(LoopGraphSpec{});
  const TrajectoryError before = trajectory_error(graph.nodes, graph.truth);
  const PoseGraphResult result = optimize_pose_graph(graph.nodes, graph.edges);
  const TrajectoryError after = trajectory_error(result.nodes, graph.truth);
  std::printf(
      "[ loop ] end %.3f -> %.3f m, rms %.3f -> %.3f m, rotation of last %.2f -> %.2f deg, %d iterations\n",
      before.end_m, after.end_m, before.rms_m, after.rms_m,
      rotation_error_deg(graph.nodes.back().cam_from_world, graph.truth.back()),
      rotation_error_deg(result.nodes.back().cam_from_world, graph.truth.back()), result.iterations);
  ASSERT_GT(before.end_m, 0.3);  // the drift is real
  EXPECT_LT(after.end_m, 0.2 * before.end_m);
  EXPECT_LT(after.rms_m, 0.5 * before.rms_m);
  EXPECT_LT(rotation_error_deg(result.nodes.back().cam_from_world, graph.truth.back()),
            0.2 * rotation_error_deg(graph.nodes.back().cam_from_world, graph.truth.back()));
  EXPECT_LT(result.final_cost, 0.1 * result.initial_cost);
  // Fixed node untouched, every scale stays 1 (fix_scale).
  EXPECT_EQ(result.nodes[0].cam_from_world.translation(), graph.nodes[0].cam_from_world.translation());
  EXPECT_EQ(result.nodes[0].cam_from_world.rotation().coeffs(),
            graph.nodes[0].cam_from_world.rotation().coeffs());
  for (const PoseGraphNode& node : result.nodes) EXPECT_DOUBLE_EQ(node.cam_from_world.scale(), 1.0);
}

TEST(PoseGraph, ConsistentGraphStaysPut) {
  // Without noise and drift every edge is satisfied: the optimum is the input itself.
  LoopGraphSpec spec;
  spec.yaw_bias_rad = 0.0;
  spec.rotation_noise_rad = 0.0;
  spec.translation_noise_m = 0.0;
  spec.neighbours = 3;
  const LoopGraph graph = make_loop_graph(spec);
  const PoseGraphResult result = optimize_pose_graph(graph.nodes, graph.edges);
  EXPECT_LT(result.initial_cost, 1e-20);
  EXPECT_LT(trajectory_error(result.nodes, graph.truth).rms_m, 1e-9);
}

TEST(PoseGraph, FreeScaleRecoversScaleDrift) {
  LoopGraphSpec spec;
  spec.yaw_bias_rad = 0.0;
  spec.scale_drift = 0.01;  // map scale 1.63 at the last node
  const LoopGraph graph = make_loop_graph(spec);
  const double last_map_scale = std::pow(1.0 + spec.scale_drift, spec.num_poses - 1);
  const TrajectoryError before = trajectory_error(graph.nodes, graph.truth);

  PoseGraphOptions options;
  options.fix_scale = false;
  const PoseGraphResult free_scale = optimize_pose_graph(graph.nodes, graph.edges, options);
  const TrajectoryError after = trajectory_error(free_scale.nodes, graph.truth);
  const PoseGraphResult fixed_scale = optimize_pose_graph(graph.nodes, graph.edges);
  const TrajectoryError after_fixed = trajectory_error(fixed_scale.nodes, graph.truth);
  const double last_scale = free_scale.nodes.back().cam_from_world.scale();
  std::printf(
      "[ scale ] end %.3f -> %.3f m (fixed scale %.3f), rms %.3f -> %.3f m (fixed scale %.3f), "
      "last scale %.4f (map %.4f)\n",
      before.end_m, after.end_m, after_fixed.end_m, before.rms_m, after.rms_m, after_fixed.rms_m, last_scale,
      last_map_scale);
  ASSERT_GT(before.end_m, 1.0);
  EXPECT_LT(after.end_m, 0.2 * before.end_m);
  EXPECT_LT(after.rms_m, 0.2 * before.rms_m);
  EXPECT_LT(after.rms_m, 0.5 * after_fixed.rms_m);  // scale drift needs the 7th dof
  EXPECT_NEAR(std::log(last_scale), std::log(last_map_scale), 0.05 * std::log(last_map_scale));
  // Node scales grow along the loop like the map scale did.
  const int middle = spec.num_poses / 2;
  EXPECT_NEAR(std::log(free_scale.nodes[middle].cam_from_world.scale()),
              middle * std::log(1.0 + spec.scale_drift), 0.1 * middle * std::log(1.0 + spec.scale_drift));
  EXPECT_DOUBLE_EQ(free_scale.nodes[0].cam_from_world.scale(), 1.0);
}

TEST(PoseGraph, EdgeWeightsPullTowardsTheHeavierMeasurement) {
  // Two nodes, node 0 fixed, two contradicting edges 0 -> 1 (translations 0 and 1 m along x):
  // the optimum is the weighted mean (Ceres stops at its default function tolerance 1e-6).
  std::vector<PoseGraphNode> nodes{{0, Sim3(), true}, {1, Sim3(), false}};
  const Sim3 a(Eigen::Quaterniond::Identity(), Vec3::Zero(), 1.0);
  const Sim3 b(Eigen::Quaterniond::Identity(), Vec3(1.0, 0.0, 0.0), 1.0);
  const std::vector<PoseGraphEdge> edges{{0, 1, a, 1.0}, {0, 1, b, 3.0}};
  const PoseGraphResult result = optimize_pose_graph(nodes, edges);
  EXPECT_NEAR(result.nodes[1].cam_from_world.translation().x(), 0.75, 1e-3);
  EXPECT_LT(result.nodes[1].cam_from_world.translation().tail<2>().norm(), 1e-9);
}

TEST(PoseGraph, UnknownIdsAndUntouchedNodes) {
  std::vector<PoseGraphNode> nodes{{0, Sim3(), true}, {1, Sim3(), false}, {7, Sim3(), false}};
  const Sim3 step(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Vec3::UnitZ())), Vec3(0.5, 0.0, 0.0), 1.0);
  const std::vector<PoseGraphEdge> edges{{0, 1, step, 1.0}, {1, 99, step, 1.0}};
  const PoseGraphResult result = optimize_pose_graph(nodes, edges);
  ASSERT_EQ(result.nodes.size(), 3u);
  EXPECT_LT((result.nodes[1].cam_from_world.translation() - step.translation()).norm(), 1e-6);
  EXPECT_LT(rotation_error_deg(result.nodes[1].cam_from_world, step), 1e-4);
  EXPECT_EQ(result.nodes[2].cam_from_world.translation(), Vec3::Zero());
}

TEST(PoseGraph, OptionsCheckNamesTheKey) {
  PoseGraphOptions options;
  EXPECT_EQ(crowdslam::test::error_of([&] { options.check(); }), "");
  options.iterations = 0;
  EXPECT_NE(crowdslam::test::error_of([&] { options.check(); }).find("iterations"), std::string::npos);
}
