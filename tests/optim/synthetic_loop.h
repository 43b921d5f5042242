#pragma once
// Synthetic loop trajectory for the pose-graph tests and benchmark (header only).
//
// Truth: num_poses cameras on a circle (rigid, scale 1). The "map" the odometry built drifts: every
// relative step k -> k+1 is the true one with a rotation bias, random rotation / translation noise,
// and a map scale that grows by (1 + scale_drift) per step (monocular drift; the translation of step k
// is expressed in the map scale sigma_k = (1 + scale_drift)^k). Initial nodes = the drifted map poses
// chained from node 0 (= truth, fixed), scale 1. Edges: map-relative transforms between each node and
// its next `neighbours` nodes (odometry / covisibility, consistent with the drifted map), plus loop edges
// first -> last carrying the true relative transforms in the map scales (what the Sim3 solver measures
// between the two keyframes; ORB-SLAM links the whole neighbourhoods of both ends).
#include <cmath>
#include <random>
#include <vector>

#include "crowdslam/geometry/sim3.h"
#include "crowdslam/optim/pose_graph.h"

namespace crowdslam::optim::test {

struct LoopGraphSpec {
  int num_poses = 50;
  double radius_m = 5.0;
  double yaw_bias_rad = 0.2 * M_PI / 180.0;  // per step, same sign: systematic drift
  double rotation_noise_rad = 0.1 * M_PI / 180.0;
  double translation_noise_m = 0.01;
  double scale_drift = 0.0;  // per step
  int neighbours = 1;
  int loop_neighbours = 1;  // loop edges between the first and the last loop_neighbours nodes (0: none)
  unsigned seed = 1;
};

struct LoopGraph {
  std::vector<geometry::Sim3> truth;  // cam_from_world, scale 1
  std::vector<PoseGraphNode> nodes;   // drifted initial guess, node 0 fixed at the truth
  std::vector<PoseGraphEdge> edges;
};

// Camera centre of a Sim3 cam_from_world (its rigid pose's centre: -R^T t / s).
inline geometry::Vec3 camera_centre(const geometry::Sim3& cam_from_world) {
  return cam_from_world.to_se3().inverse().translation();
}

inline LoopGraph make_loop_graph(const LoopGraphSpec& spec) {
  using geometry::Sim3;
  using geometry::Vec3;
  std::mt19937 rng(spec.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  LoopGraph graph;
  for (int k = 0; k < spec.num_poses; ++k) {
    // Camera looks along the tangent of the circle (x-z plane, y down), slight pitch oscillation.
    const double angle = 2.0 * M_PI * k / spec.num_poses;
    const Vec3 centre(spec.radius_m * std::cos(angle), 0.1 * std::sin(3.0 * angle),
                      spec.radius_m * std::sin(angle));
    const Eigen::Quaterniond world_from_cam(Eigen::AngleAxisd(-angle, Vec3::UnitY()) *
                                            Eigen::AngleAxisd(0.05 * std::sin(2.0 * angle), Vec3::UnitX()));
    graph.truth.push_back(Sim3(world_from_cam, centre, 1.0).inverse());
  }
  // Drifted map: map_k = step_(k-1) * map_(k-1).
  std::vector<Sim3> map{graph.truth[0]};
  double map_scale = 1.0;
  for (int k = 0; k + 1 < spec.num_poses; ++k) {
    const Sim3 true_step = graph.truth[k + 1] * graph.truth[k].inverse();
    const Vec3 axis = Vec3(noise(rng), noise(rng), noise(rng)).normalized();
    const Eigen::Quaterniond rotation_error(Eigen::AngleAxisd(spec.yaw_bias_rad, Vec3::UnitY()) *
                                            Eigen::AngleAxisd(spec.rotation_noise_rad * noise(rng), axis));
    const Vec3 translation = map_scale * true_step.translation() +
                             spec.translation_noise_m * Vec3(noise(rng), noise(rng), noise(rng));
    const Sim3 step(rotation_error * true_step.rotation(), translation, 1.0);
    map.push_back(step * map.back());
    map_scale *= 1.0 + spec.scale_drift;
  }
  for (int k = 0; k < spec.num_poses; ++k) graph.nodes.push_back({k, map[k], k == 0});
  for (int k = 0; k < spec.num_poses; ++k) {
    for (int j = k + 1; j <= k + spec.neighbours && j < spec.num_poses; ++j) {
      graph.edges.push_back({k, j, map[j] * map[k].inverse(), 1.0});
    }
  }
  // Loop edges i -> j (i among the first loop_neighbours nodes, j among the last ones): the true
  // relative transform in the map scales, sigma_j * T_j * T_i^-1 * sigma_i^-1.
  auto map_scale_at = [&](int k) { return std::pow(1.0 + spec.scale_drift, k); };
  const int last = spec.num_poses - 1;
  for (int i = 0; i < spec.loop_neighbours; ++i) {
    for (int j = last; j > last - spec.loop_neighbours; --j) {
      const Sim3 scale_j(Eigen::Quaterniond::Identity(), Vec3::Zero(), map_scale_at(j));
      const Sim3 scale_i(Eigen::Quaterniond::Identity(), Vec3::Zero(), map_scale_at(i));
      graph.edges.push_back(
          {i, j, scale_j * graph.truth[j] * graph.truth[i].inverse() * scale_i.inverse(), 1.0});
    }
  }
  return graph;
}

// RMS distance of the node camera centres to the truth, and the error of the last node.
struct TrajectoryError {
  double rms_m = 0.0;
  double end_m = 0.0;
};

inline TrajectoryError trajectory_error(const std::vector<PoseGraphNode>& nodes,
                                        const std::vector<geometry::Sim3>& truth) {
  TrajectoryError error;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const double d = (camera_centre(nodes[k].cam_from_world) - camera_centre(truth[k])).norm();
    error.rms_m += d * d;
  }
  error.rms_m = std::sqrt(error.rms_m / nodes.size());
  error.end_m = (camera_centre(nodes.back().cam_from_world) - camera_centre(truth.back())).norm();
  return error;
}

}  // namespace crowdslam::optim::test
