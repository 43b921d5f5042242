#pragma once
// Pose-graph (essential-graph) optimisation over Sim3 keyframe poses for loop closing, on plain data.
//
// Nodes are cam_from_world similarities; an edge measures the relative transform
// S_to,from (= S_to,w * S_w,from). Per edge the residual is the 7-vector
//   E = S_to,from_measured^-1 * S_to,w * S_from,w^-1,   r = sqrt(weight) * (t_E, angle_axis(R_E), log s_E)
// (first-order equal to the sim(3) log of E; identity information as ORB-SLAM). Ceres
// Levenberg-Marquardt, automatic differentiation; per node a quaternion (EigenQuaternionManifold), a
// translation and a log scale. Fixed nodes do not move. With fix_scale every node keeps its input scale
// (1 for RGB-D / stereo): 6-dof nodes; otherwise 7-dof.
//
// Global bundle adjustment after a loop closure reuses optim::local_bundle_adjustment
// (bundle_adjustment.h) with every keyframe; bench/bench_optim.cpp measures it at global-map size.
#include <vector>

#include "crowdslam/geometry/sim3.h"

namespace crowdslam::optim {

struct PoseGraphNode {
  int id = -1;
  geometry::Sim3 cam_from_world;
  bool fixed = false;
};

// Measured relative transform: S_to,w = to_from_from * S_from,w.
struct PoseGraphEdge {
  int from_id = -1;
  int to_id = -1;
  geometry::Sim3 to_from_from;
  double weight = 1.0;  // information (residual scaled by sqrt(weight))
};

struct PoseGraphOptions {
  int iterations = 20;
  bool fix_scale = true;  // every node keeps its input scale (RGB-D / stereo: 1)

  // Throws InputError naming the bad option. Not called by optimize_pose_graph.
  void check() const;
};

struct PoseGraphResult {
  std::vector<PoseGraphNode> nodes;  // input order; fixed ones unchanged
  double initial_cost = 0.0;         // Ceres cost (0.5 * sum of squared residuals)
  double final_cost = 0.0;
  int iterations = 0;  // Ceres iterations (successful and unsuccessful steps)
};

// Edges must reference node ids present in `nodes` (edges with unknown ids are skipped); node ids are
// unique. Nodes that no edge touches are returned unchanged.
PoseGraphResult optimize_pose_graph(const std::vector<PoseGraphNode>& nodes,
                                    const std::vector<PoseGraphEdge>& edges,
                                    const PoseGraphOptions& options = {});

}  // namespace crowdslam::optim
