#include "crowdslam/optim/pose_optimizer.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>

#include "crowdslam/optim/se3_update.h"
#include "crowdslam/util/error.h"

namespace crowdslam::optim {

using geometry::PinholeCamera;
using geometry::SE3;
using geometry::Vec2;
using geometry::Vec3;
using geometry::Vec6;
using Mat6 = Eigen::Matrix<double, 6, 6>;

void PoseOptimizerOptions::check() const {
  auto fail = [](const std::string& key, double value) {
    return InputError("pose optimizer: " + key + " is invalid: " + std::to_string(value));
  };
  if (rounds < 1) throw fail("rounds (must be >= 1)", rounds);
  if (iterations_per_round < 1) throw fail("iterations_per_round (must be >= 1)", iterations_per_round);
  if (robust_rounds < 0) throw fail("robust_rounds (must be >= 0)", robust_rounds);
  if (!(chi2_mono > 0.0)) throw fail("chi2_mono (must be > 0)", chi2_mono);
  if (!(chi2_stereo > 0.0)) throw fail("chi2_stereo (must be > 0)", chi2_stereo);
  if (min_observations < 3) throw fail("min_observations (must be >= 3)", min_observations);
}

namespace {

constexpr double kMinDepth = 1e-6;
// Cost of an active observation that a trial step moves behind the camera: large, so LM rejects it.
constexpr double kBehindCameraCost = 1e8;

struct Residual {
  bool valid = false;  // point in front of the camera
  bool stereo = false;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();  // predicted - observed (u, v[, u_r])
  double chi2 = 0.0;
  Vec3 p_cam = Vec3::Zero();
};

// Rotation as a matrix: applied once per observation and pass, cheaper than the quaternion.
struct Rigid {
  explicit Rigid(const SE3& pose) : rotation(pose.rotation_matrix()), translation(pose.translation()) {}
  geometry::Mat3 rotation;
  Vec3 translation;
};

// Upper triangle of h += w * j * j^T (Eigen's rankUpdate goes through its GEMM path: slow at 6x6).
inline void add_rank_one(const Vec6& j, double w, Mat6& h) {
  for (int col = 0; col < 6; ++col) {
    const double wj = w * j(col);
    for (int row = 0; row <= col; ++row) h(row, col) += wj * j(row);
  }
}

class PoseProblem {
 public:
  PoseProblem(const PinholeCamera& camera, const std::vector<PoseObservation>& observations,
              const PoseOptimizerOptions& options)
      : camera_(camera), observations_(observations), options_(options) {}

  [[nodiscard]] bool is_stereo(const PoseObservation& obs) const { return obs.is_stereo() && camera_.bf > 0.0; }
  [[nodiscard]] double threshold(const PoseObservation& obs) const {
    return is_stereo(obs) ? options_.chi2_stereo : options_.chi2_mono;
  }

  [[nodiscard]] Residual residual(const Rigid& pose, const PoseObservation& obs) const {
    Residual r;
    r.stereo = is_stereo(obs);
    r.p_cam.noalias() = pose.rotation * obs.point_world;
    r.p_cam += pose.translation;
    if (!(r.p_cam.z() > kMinDepth)) return r;
    r.valid = true;
    const Vec2 predicted = camera_.project(r.p_cam);
    r.error.head<2>() = predicted - obs.pixel;
    r.error.z() = r.stereo ? camera_.right_u(predicted.x(), r.p_cam.z()) - obs.right_u : 0.0;
    r.chi2 = obs.inv_sigma2 * r.error.squaredNorm();
    return r;
  }

  // Huber rho(chi2) with delta^2 = the observation's chi2 threshold.
  [[nodiscard]] static double robust_cost(double chi2, double delta2, bool robust) {
    if (!robust || chi2 <= delta2) return chi2;
    return 2.0 * std::sqrt(delta2 * chi2) - delta2;
  }
  [[nodiscard]] static double huber_weight(double chi2, double delta2, bool robust) {
    if (!robust || chi2 <= delta2) return 1.0;
    return std::sqrt(delta2 / chi2);
  }

  // 0.5 * sum rho(chi2) over active observations.
  [[nodiscard]] double cost(const SE3& se3, const std::vector<bool>& active, bool robust) const {
    const Rigid pose(se3);
    double total = 0.0;
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      if (!active[i]) continue;
      const Residual r = residual(pose, observations_[i]);
      total += r.valid ? robust_cost(r.chi2, threshold(observations_[i]), robust) : kBehindCameraCost;
    }
    return 0.5 * total;
  }

  // Gauss-Newton normal equations with IRLS Huber weights; returns the cost at `pose`.
  double linearize(const SE3& se3, const std::vector<bool>& active, bool robust, Mat6& h, Vec6& g) const {
    const Rigid pose(se3);
    h.setZero();
    g.setZero();
    double total = 0.0;
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      if (!active[i]) continue;
      const PoseObservation& obs = observations_[i];
      const Residual r = residual(pose, obs);
      if (!r.valid) {
        total += kBehindCameraCost;
        continue;
      }
      const double delta2 = threshold(obs);
      total += robust_cost(r.chi2, delta2, robust);
      const double w = obs.inv_sigma2 * huber_weight(r.chi2, delta2, robust);
      // Closed form of projection_jacobian * point_jacobian_wrt_pose (se3_update.h), one row each.
      const double inv_z = 1.0 / r.p_cam.z();
      const double xz = r.p_cam.x() * inv_z;
      const double yz = r.p_cam.y() * inv_z;
      const double fx = camera_.fx;
      const double fy = camera_.fy;
      Vec6 ju;
      Vec6 jv;
      ju << fx * inv_z, 0.0, -fx * xz * inv_z, -fx * xz * yz, fx * (1.0 + xz * xz), -fx * yz;
      jv << 0.0, fy * inv_z, -fy * yz * inv_z, -fy * (1.0 + yz * yz), fy * xz * yz, fy * xz;
      add_rank_one(ju, w, h);
      add_rank_one(jv, w, h);
      g += (w * r.error.x()) * ju + (w * r.error.y()) * jv;
      if (r.stereo) {
        // u_r = u - bf / z: d(-bf / z) / d delta = bf / z^2 * (0, 0, 1, y, -x, 0).
        const double k = camera_.bf * inv_z * inv_z;
        Vec6 jr = ju;
        jr(2) += k;
        jr(3) += k * r.p_cam.y();
        jr(4) -= k * r.p_cam.x();
        add_rank_one(jr, w, h);
        g += (w * r.error.z()) * jr;
      }
    }
    h.triangularView<Eigen::StrictlyLower>() = h.transpose();
    return 0.5 * total;
  }

  // Levenberg-Marquardt on the active set; every trial step counts as one iteration.
  int run_lm(SE3& pose, const std::vector<bool>& active, bool robust, int max_iterations) const {
    Mat6 h;
    Vec6 g;
    double cost_now = linearize(pose, active, robust, h, g);
    double lambda = 1e-5 * std::max(h.diagonal().maxCoeff(), 1e-12);
    double nu = 2.0;
    int iteration = 0;
    while (iteration < max_iterations) {
      ++iteration;
      Mat6 damped = h;
      damped.diagonal().array() += lambda;
      const Vec6 step = damped.ldlt().solve(-g);
      if (!step.allFinite()) break;
      const SE3 candidate = left_update(step, pose);
      const double cost_new = cost(candidate, active, robust);
      if (cost_new < cost_now) {
        const double predicted = 0.5 * step.dot(lambda * step - g);
        const double rho = (cost_now - cost_new) / std::max(predicted, 1e-300);
        pose = candidate;
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
        nu = 2.0;
        if (step.squaredNorm() < 1e-20 || cost_now - cost_new <= 1e-12 * cost_now) break;  // converged
        cost_now = linearize(pose, active, robust, h, g);
      } else {
        lambda *= nu;
        nu *= 2.0;
        if (step.squaredNorm() < 1e-20 || lambda > 1e20) break;  // no further progress possible
      }
    }
    return iteration;
  }

  // Classifies every observation at `pose`; returns the number of inliers.
  int classify(const SE3& se3, std::vector<bool>& inliers) const {
    const Rigid pose(se3);
    int count = 0;
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      const Residual r = residual(pose, observations_[i]);
      inliers[i] = r.valid && r.chi2 <= threshold(observations_[i]);
      count += inliers[i] ? 1 : 0;
    }
    return count;
  }

 private:
  const PinholeCamera& camera_;
  const std::vector<PoseObservation>& observations_;
  const PoseOptimizerOptions& options_;
};

}  // namespace

PoseOptimizationResult optimize_pose(const PinholeCamera& camera, const SE3& initial_cam_from_world,
                                     const std::vector<PoseObservation>& observations,
                                     const PoseOptimizerOptions& options) {
  PoseOptimizationResult result;
  result.cam_from_world = initial_cam_from_world;
  result.inliers.assign(observations.size(), false);
  if (static_cast<int>(observations.size()) < options.min_observations) return result;

  const PoseProblem problem(camera, observations, options);
  SE3 pose = initial_cam_from_world;
  std::vector<bool> active(observations.size(), true);
  int num_inliers = 0;
  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    result.iterations += problem.run_lm(pose, active, robust, options.iterations_per_round);
    num_inliers = problem.classify(pose, active);
    if (num_inliers < options.min_observations) break;
  }
  if (!pose.translation().allFinite() || !pose.rotation().coeffs().allFinite()) return result;
  result.success = true;
  result.cam_from_world = pose;
  result.inliers = active;
  result.num_inliers = num_inliers;
  return result;
}

}  // namespace crowdslam::optim
