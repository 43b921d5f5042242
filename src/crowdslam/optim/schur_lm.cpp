#include "crowdslam/optim/schur_lm.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "crowdslam/optim/schur_kernel.h"
#include "crowdslam/optim/se3_update.h"

namespace crowdslam::optim {

using geometry::Mat3;
using geometry::SE3;
using geometry::Vec3;
using geometry::Vec6;

namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat63 = Eigen::Matrix<double, 6, 3>;

constexpr double kMinDiagonal = 1e-6;   // Ceres' min_lm_diagonal / max_lm_diagonal
constexpr double kMaxDiagonal = 1e32;
constexpr double kInitialMu = 1e-4;  // 1 / Ceres' initial_trust_region_radius
constexpr double kMinMu = 1e-16;     // 1 / max_trust_region_radius
constexpr double kMaxMu = 1e32;      // 1 / min_trust_region_radius
constexpr double kMinRelativeDecrease = 1e-3;
constexpr double kFunctionTolerance = 1e-6;
constexpr double kParameterTolerance = 1e-8;

double huber_rho(double s, double delta) {
  if (delta <= 0.0 || s <= delta * delta) return s;
  return 2.0 * delta * std::sqrt(s) - delta * delta;
}

double huber_weight(double s, double delta) {
  if (delta <= 0.0 || s <= delta * delta) return 1.0;
  return delta / std::sqrt(s);
}

class Problem {
 public:
  Problem(const geometry::PinholeCamera& camera, const std::vector<SchurObservation>& observations)
      : camera_(camera), observations_(observations) {}

  // Whitened residual (third row 0 for mono) and the camera-frame point; false if |z| is too small.
  bool residual(const Mat3& rotation, const SE3& pose, const Vec3& point, const SchurObservation& o, Vec3& r,
                Vec3& p_cam) const {
    p_cam = rotation * point + pose.translation();
    if (o.plane) {
      r << o.sqrt_information * (o.normal.dot(p_cam) - o.distance), 0.0, 0.0;
      return true;
    }
    if (std::abs(p_cam.z()) < kMinAbsDepth) return false;
    const double inv_z = 1.0 / p_cam.z();
    const double u = camera_.fx * p_cam.x() * inv_z + camera_.cx;
    r(0) = o.sqrt_information * (u - o.pixel.x());
    r(1) = o.sqrt_information * (camera_.fy * p_cam.y() * inv_z + camera_.cy - o.pixel.y());
    r(2) = o.stereo ? o.sqrt_information * (u - camera_.bf * inv_z - o.right_u) : 0.0;
    return true;
  }

  // 1/2 sum rho; false if some observation cannot be evaluated.
  bool cost(const std::vector<SE3>& poses, const std::vector<Mat3>& rotations,
            const std::vector<Vec3>& points, double& total) const {
    total = 0.0;
    Vec3 r;
    Vec3 p_cam;
    for (const SchurObservation& o : observations_) {
      if (!residual(rotations[o.pose], poses[o.pose], points[o.point], o, r, p_cam)) return false;
      total += huber_rho(r.squaredNorm(), o.huber_delta);
    }
    total *= 0.5;
    return true;
  }

  // d r / d p_cam (whitened; third row 0 for mono).
  [[nodiscard]] Mat3 d_residual(const SchurObservation& o, const Vec3& p_cam) const {
    Mat3 d;
    if (o.plane) {
      d.setZero();
      d.row(0) = o.normal.transpose();
      return o.sqrt_information * d;
    }
    d.topRows<2>() = projection_jacobian(camera_.fx, camera_.fy, p_cam);
    if (o.stereo) {
      d.row(2) = right_u_jacobian(camera_.fx, camera_.bf, p_cam);
    } else {
      d.row(2).setZero();
    }
    return o.sqrt_information * d;
  }

 private:
  const geometry::PinholeCamera& camera_;
  const std::vector<SchurObservation>& observations_;
};

// A relative pose's residual and the Jacobian of it for pose b (pose a's is the identity).
Vec6 relative_error(const std::vector<SE3>& poses, const SchurRelativePose& edge, Mat6* jacobian_b = nullptr) {
  return relative_pose_error(poses[edge.pose_a], poses[edge.pose_b], edge.a_from_b, jacobian_b);
}

double relative_cost(const std::vector<SE3>& poses, const std::vector<SchurRelativePose>& edges) {
  double total = 0.0;
  for (const SchurRelativePose& edge : edges) {
    const Vec6 e = relative_error(poses, edge);
    total += e.cwiseProduct(edge.weight).dot(e);
  }
  return total;
}

std::vector<Mat3> rotations_of(const std::vector<SE3>& poses) {
  std::vector<Mat3> rotations;
  rotations.reserve(poses.size());
  for (const SE3& pose : poses) rotations.push_back(pose.rotation_matrix());
  return rotations;
}

template <int N>
Eigen::Matrix<double, N, 1> clamped_diagonal(const Eigen::Matrix<double, N, N>& h) {
  return h.diagonal().cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal);
}

}  // namespace

SchurLmSummary solve_schur_lm(const geometry::PinholeCamera& camera, std::vector<SE3>& poses,
                              const std::vector<bool>& fixed, std::vector<Vec3>& points,
                              const std::vector<SchurObservation>& observations, int max_iterations,
                              const std::atomic<bool>* abort_flag,
                              const std::vector<SchurRelativePose>& relative_poses) {
  SchurLmSummary summary;
  const Problem problem(camera, observations);
  std::vector<Mat3> rotations = rotations_of(poses);
  // Observations' cost plus the relative poses'.
  auto total_cost = [&](const std::vector<SE3>& at, const std::vector<Mat3>& rotations_at,
                        const std::vector<Vec3>& points_at, double& total) {
    if (!problem.cost(at, rotations_at, points_at, total)) return false;
    total += 0.5 * relative_cost(at, relative_poses);
    return true;
  };
  double cost = 0.0;
  if (!total_cost(poses, rotations, points, cost)) {
    summary.valid = false;
    return summary;
  }
  summary.initial_cost = summary.final_cost = cost;
  if (observations.empty() && relative_poses.empty()) return summary;

  const auto num_poses = static_cast<int>(poses.size());
  const auto num_points = static_cast<int>(points.size());
  std::vector<int> free_index(poses.size(), -1);
  int num_free = 0;
  for (int k = 0; k < num_poses; ++k) {
    if (!fixed[k]) free_index[k] = num_free++;
  }
  // Observations grouped by point (compressed rows).
  std::vector<int> point_start(points.size() + 1, 0);
  for (const SchurObservation& o : observations) ++point_start[o.point + 1];
  for (int p = 0; p < num_points; ++p) point_start[p + 1] += point_start[p];
  std::vector<int> by_point(observations.size());
  {
    std::vector<int> next(point_start.begin(), point_start.end() - 1);
    for (size_t i = 0; i < observations.size(); ++i)
      by_point[next[observations[i].point]++] = static_cast<int>(i);
  }

  // Off-diagonal blocks of the relative poses between two free poses (upper triangle: row < column).
  struct Coupling {
    int row = 0;
    int col = 0;
    Mat6 block;
  };
  std::vector<Coupling> couplings;
  std::vector<Mat6> u(num_free);
  std::vector<Vec6> g_pose(num_free);
  std::vector<Mat3> v(points.size());
  std::vector<Vec3> g_point(points.size());
  std::vector<Mat63> w(observations.size());
  std::vector<Mat3> v_inverse(points.size());
  std::vector<Vec6> d_pose(num_free);
  std::vector<Vec3> d_point(points.size());
  std::vector<SE3> trial_poses;
  std::vector<Vec3> trial_points;
  Eigen::MatrixXd s(6 * num_free, 6 * num_free);
  // Scratch of the pair kernel: one point's free observations (W V^-1, W, pose index).
  int max_per_point = 0;
  for (int p = 0; p < num_points; ++p)
    max_per_point = std::max(max_per_point, point_start[p + 1] - point_start[p]);
  std::vector<double> pair_y(18 * static_cast<size_t>(max_per_point));
  std::vector<double> pair_w(18 * static_cast<size_t>(max_per_point));
  std::vector<int> pair_pose(static_cast<size_t>(max_per_point));
  const schur_kernel::SubtractPairs subtract_pairs = schur_kernel::subtract_pairs();
  Eigen::VectorXd rhs(6 * num_free);
  double mu = kInitialMu;
  double nu = 2.0;
  bool linearize = true;

  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    if (iteration > 0 && abort_flag != nullptr && abort_flag->load(std::memory_order_relaxed)) break;
    if (linearize) {
      for (auto& m : u) m.setZero();
      for (auto& g : g_pose) g.setZero();
      for (auto& m : v) m.setZero();
      for (auto& g : g_point) g.setZero();
      Vec3 r;
      Vec3 p_cam;
      for (size_t i = 0; i < observations.size(); ++i) {
        const SchurObservation& o = observations[i];
        w[i].setZero();
        if (!problem.residual(rotations[o.pose], poses[o.pose], points[o.point], o, r, p_cam)) continue;
        const double weight = huber_weight(r.squaredNorm(), o.huber_delta);
        const Mat3 d = problem.d_residual(o, p_cam);
        const Mat3 j_point = d * rotations[o.pose];
        // The weighted transposes first: products of plain fixed-size matrices (a scalar inside a lazy
        // product made Eigen evaluate these coefficient by coefficient, 5 % of a run's instructions).
        const Mat3 j_point_tw = weight * j_point.transpose();
        v[o.point].noalias() += j_point_tw * j_point;
        g_point[o.point].noalias() += j_point_tw * r;
        const int f = free_index[o.pose];
        if (f < 0) continue;
        const Eigen::Matrix<double, 3, 6> j_pose = d * point_jacobian_wrt_pose(p_cam);
        const Mat63 j_pose_tw = weight * j_pose.transpose();
        u[f].noalias() += j_pose_tw * j_pose;
        g_pose[f].noalias() += j_pose_tw * r;
        w[i].noalias() = j_pose_tw * j_point;
      }
      couplings.clear();
      for (const SchurRelativePose& edge : relative_poses) {
        Mat6 j_b;
        const Vec6 e = relative_error(poses, edge, &j_b);
        const Vec6 we = edge.weight.cwiseProduct(e);
        const int fa = free_index[edge.pose_a];
        const int fb = free_index[edge.pose_b];
        const Mat6 wj_b = edge.weight.asDiagonal() * j_b;
        if (fa >= 0) {
          u[fa].diagonal() += edge.weight;
          g_pose[fa] += we;
        }
        if (fb >= 0) {
          u[fb].noalias() += j_b.transpose() * wj_b;
          g_pose[fb].noalias() += j_b.transpose() * we;
        }
        if (fa >= 0 && fb >= 0) {
          // J_a^T W J_b with J_a = I.
          if (fa < fb) couplings.push_back({fa, fb, wj_b});
          else couplings.push_back({fb, fa, wj_b.transpose()});
        }
      }
      linearize = false;
    }

    // Damped normal equations, points eliminated: S d_pose = rhs (upper triangle of S filled).
    s.setZero();
    for (int f = 0; f < num_free; ++f) {
      Mat6 block = u[f];
      block.diagonal() += mu * clamped_diagonal<6>(u[f]);
      s.block<6, 6>(6 * f, 6 * f) = block;
      rhs.segment<6>(6 * f) = -g_pose[f];
    }
    for (const Coupling& c : couplings) s.block<6, 6>(6 * c.row, 6 * c.col) += c.block;
    for (int p = 0; p < num_points; ++p) {
      const int begin = point_start[p];
      const int end = point_start[p + 1];
      if (begin == end) continue;
      Mat3 damped = v[p];
      damped.diagonal() += mu * clamped_diagonal<3>(v[p]);
      bool invertible = false;
      damped.computeInverseWithCheck(v_inverse[p], invertible);
      if (!invertible) v_inverse[p].setZero();
      const Vec3 b_point = -g_point[p];
      // The point's free observations in plain arrays for the pair kernel (schur_kernel.h).
      int m = 0;
      for (int a = begin; a < end; ++a) {
        const int ia = by_point[a];
        const int fa = free_index[observations[ia].pose];
        if (fa < 0) continue;
        Eigen::Map<Mat63> y(pair_y.data() + 18 * m);
        y.noalias() = w[ia] * v_inverse[p];
        rhs.segment<6>(6 * fa).noalias() -= y * b_point;
        Eigen::Map<Mat63>(pair_w.data() + 18 * m) = w[ia];
        pair_pose[m] = fa;
        ++m;
      }
      subtract_pairs({pair_y.data(), pair_w.data(), pair_pose.data(), m}, s.data(), s.outerStride());
    }
    const Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt(s);
    if (num_free > 0 && llt.info() != Eigen::Success) {
      ++summary.unsuccessful_steps;
      mu *= nu;
      nu *= 2.0;
      if (mu > kMaxMu) break;
      continue;
    }
    const Eigen::VectorXd pose_step = num_free > 0 ? Eigen::VectorXd(llt.solve(rhs)) : Eigen::VectorXd();
    double model_decrease = 0.0;
    double step_norm2 = 0.0;
    double state_norm2 = 0.0;
    for (int f = 0; f < num_free; ++f) {
      d_pose[f] = pose_step.segment<6>(6 * f);
      const Vec6 damping = mu * clamped_diagonal<6>(u[f]).cwiseProduct(d_pose[f]);
      model_decrease += d_pose[f].dot(damping - g_pose[f]);
      step_norm2 += d_pose[f].squaredNorm();
    }
    for (int p = 0; p < num_points; ++p) {
      d_point[p].setZero();
      const int begin = point_start[p];
      const int end = point_start[p + 1];
      if (begin == end) continue;
      Vec3 b = -g_point[p];
      for (int a = begin; a < end; ++a) {
        const int ia = by_point[a];
        const int fa = free_index[observations[ia].pose];
        if (fa >= 0) b.noalias() -= w[ia].transpose() * d_pose[fa];
      }
      d_point[p] = v_inverse[p] * b;
      const Vec3 damping = mu * clamped_diagonal<3>(v[p]).cwiseProduct(d_point[p]);
      model_decrease += d_point[p].dot(damping - g_point[p]);
      step_norm2 += d_point[p].squaredNorm();
      state_norm2 += points[p].squaredNorm();
    }
    model_decrease *= 0.5;
    for (int k = 0; k < num_poses; ++k) {
      if (free_index[k] >= 0) state_norm2 += poses[k].translation().squaredNorm() + 1.0;
    }
    if (std::sqrt(step_norm2) <= (std::sqrt(state_norm2) + kParameterTolerance) * kParameterTolerance) break;

    trial_poses = poses;
    for (int k = 0; k < num_poses; ++k) {
      if (free_index[k] >= 0) trial_poses[k] = left_update(d_pose[free_index[k]], poses[k]);
    }
    trial_points = points;
    for (int p = 0; p < num_points; ++p) trial_points[p] += d_point[p];
    std::vector<Mat3> trial_rotations = rotations_of(trial_poses);
    double trial_cost = 0.0;
    const bool valid = total_cost(trial_poses, trial_rotations, trial_points, trial_cost);
    const double ratio = valid && model_decrease > 0.0 ? (cost - trial_cost) / model_decrease : -1.0;
    if (ratio > kMinRelativeDecrease) {
      const bool converged = std::abs(cost - trial_cost) <= kFunctionTolerance * cost;
      poses.swap(trial_poses);
      points.swap(trial_points);
      rotations.swap(trial_rotations);
      cost = trial_cost;
      ++summary.successful_steps;
      mu = std::max(kMinMu, mu * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3)));
      nu = 2.0;
      linearize = true;
      if (converged) break;
    } else {
      ++summary.unsuccessful_steps;
      mu *= nu;
      nu *= 2.0;
      if (mu > kMaxMu) break;
    }
  }
  summary.final_cost = cost;
  return summary;
}

}  // namespace crowdslam::optim
