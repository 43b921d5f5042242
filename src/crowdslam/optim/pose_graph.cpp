#include "crowdslam/optim/pose_graph.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cassert>
#include <cmath>
#include <string>
#include <unordered_map>

#include "crowdslam/optim/bundle_adjustment.h"
#include "crowdslam/util/error.h"

namespace crowdslam::optim {

using geometry::Sim3;
using geometry::Vec3;

void PoseGraphOptions::check() const {
  if (iterations < 1) {
    throw InputError("pose graph: iterations (must be >= 1) is invalid: " + std::to_string(iterations));
  }
}

namespace {

// Per node: quaternion (x, y, z, w), translation, log scale of cam_from_world.
struct NodeBlock {
  double quaternion[4];
  double translation[3];
  double log_scale[1];

  explicit NodeBlock(const Sim3& s) {
    const Eigen::Quaterniond& q = s.rotation();
    quaternion[0] = q.x();
    quaternion[1] = q.y();
    quaternion[2] = q.z();
    quaternion[3] = q.w();
    for (int i = 0; i < 3; ++i) translation[i] = s.translation()(i);
    log_scale[0] = std::log(s.scale());
  }
  [[nodiscard]] Sim3 sim3() const {
    const Eigen::Quaterniond q(quaternion[3], quaternion[0], quaternion[1], quaternion[2]);
    return Sim3(q, Vec3(translation[0], translation[1], translation[2]), std::exp(log_scale[0]));
  }
};

// r = sqrt(w) (t_E, angle_axis(R_E), log s_E) of E = measured^-1 * S_to * S_from^-1.
struct RelativeSim3Error {
  RelativeSim3Error(const Sim3& to_from_from, double weight)
      : measured_rotation_inverse(to_from_from.rotation().conjugate()),
        measured_translation(to_from_from.translation()),
        measured_log_scale(std::log(to_from_from.scale())),
        sqrt_weight(std::sqrt(weight)) {}

  template <typename T>
  bool operator()(const T* q_from_data, const T* t_from_data, const T* log_s_from, const T* q_to_data,
                  const T* t_to_data, const T* log_s_to, T* residual) const {
    using std::exp;
    using Quat = Eigen::Quaternion<T>;
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Quat> q_from(q_from_data);
    const Eigen::Map<const Quat> q_to(q_to_data);
    const Eigen::Map<const V3> t_from(t_from_data);
    const Eigen::Map<const V3> t_to(t_to_data);
    // Estimated S_to,from = S_to * S_from^-1.
    const Quat q_from_inv = q_from.conjugate();
    const Quat q_est = q_to * q_from_inv;
    const T scale_ratio = exp(log_s_to[0] - log_s_from[0]);
    const V3 t_est = t_to - scale_ratio * (q_est * t_from);
    // E = measured^-1 * estimated.
    const Quat q_measured_inv = measured_rotation_inverse.cast<T>();
    const Quat q_error = q_measured_inv * q_est;
    const T log_s_error = log_s_to[0] - log_s_from[0] - T(measured_log_scale);
    const V3 t_error =
        (q_measured_inv * (t_est - measured_translation.cast<T>())) * T(std::exp(-measured_log_scale));
    const T q_wxyz[4] = {q_error.w(), q_error.x(), q_error.y(), q_error.z()};
    T angle_axis[3];
    ceres::QuaternionToAngleAxis(q_wxyz, angle_axis);
    const T w = T(sqrt_weight);
    for (int i = 0; i < 3; ++i) {
      residual[i] = w * t_error(i);
      residual[3 + i] = w * angle_axis[i];
    }
    residual[6] = w * log_s_error;
    return true;
  }

  Eigen::Quaterniond measured_rotation_inverse;
  Vec3 measured_translation;
  double measured_log_scale;
  double sqrt_weight;
};

}  // namespace

PoseGraphResult optimize_pose_graph(const std::vector<PoseGraphNode>& nodes,
                                    const std::vector<PoseGraphEdge>& edges,
                                    const PoseGraphOptions& options) {
  PoseGraphResult result;
  result.nodes = nodes;
  std::vector<NodeBlock> blocks;
  blocks.reserve(nodes.size());
  std::unordered_map<int, std::size_t> index;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const bool inserted = index.emplace(nodes[i].id, i).second;
    assert(inserted && "duplicate node id");
    (void)inserted;
    blocks.emplace_back(nodes[i].cam_from_world);
  }

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion_manifold;
  std::vector<bool> added(nodes.size(), false);
  auto add_node = [&](std::size_t i) {
    if (added[i]) return;
    added[i] = true;
    NodeBlock& b = blocks[i];
    problem.AddParameterBlock(b.quaternion, 4, &quaternion_manifold);
    problem.AddParameterBlock(b.translation, 3);
    problem.AddParameterBlock(b.log_scale, 1);
    if (nodes[i].fixed) {
      problem.SetParameterBlockConstant(b.quaternion);
      problem.SetParameterBlockConstant(b.translation);
    }
    if (nodes[i].fixed || options.fix_scale) problem.SetParameterBlockConstant(b.log_scale);
  };
  using Cost = ceres::AutoDiffCostFunction<RelativeSim3Error, 7, 4, 3, 1, 4, 3, 1>;
  for (const PoseGraphEdge& edge : edges) {
    const auto from = index.find(edge.from_id);
    const auto to = index.find(edge.to_id);
    if (from == index.end() || to == index.end() || from->second == to->second) continue;
    add_node(from->second);
    add_node(to->second);
    NodeBlock& a = blocks[from->second];
    NodeBlock& b = blocks[to->second];
    problem.AddResidualBlock(new Cost(new RelativeSim3Error(edge.to_from_from, edge.weight)), nullptr,
                             a.quaternion, a.translation, a.log_scale, b.quaternion, b.translation,
                             b.log_scale);
  }
  if (problem.NumResidualBlocks() == 0) return result;

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type =
      ceres_has_sparse_backend() ? ceres::SPARSE_NORMAL_CHOLESKY : ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.iterations;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (added[i] && !nodes[i].fixed) result.nodes[i].cam_from_world = blocks[i].sim3();
  }
  return result;
}

}  // namespace crowdslam::optim
