#include "crowdslam/optim/sim3_optimization.h"

#include <ceres/ceres.h>

#include <cassert>
#include <cmath>
#include <limits>
#include <string>

#include "crowdslam/util/error.h"

namespace crowdslam::optim {

using geometry::PinholeCamera;
using geometry::Sim3;
using geometry::Sim3Match;
using geometry::Vec3;

void Sim3OptimizationOptions::check() const {
  auto fail = [](const std::string& key, double value) {
    return InputError("sim3 optimization: " + key + " is invalid: " + std::to_string(value));
  };
  if (!(chi2 > 0.0)) throw fail("chi2 (must be > 0)", chi2);
  if (iterations_first < 1) throw fail("iterations_first (must be >= 1)", iterations_first);
  if (iterations_second < 0) throw fail("iterations_second (must be >= 0)", iterations_second);
}

namespace {

// Reprojection of a fixed point through cam1_from_cam2 (forward) or its inverse (backward).
// Parameters: quaternion (x, y, z, w), translation, log scale.
struct Sim3ProjectionError {
  Sim3ProjectionError(const PinholeCamera& camera, const Vec3& point, const Eigen::Vector2d& pixel,
                      double sigma2, bool inverse)
      : fx(camera.fx),
        fy(camera.fy),
        cx(camera.cx),
        cy(camera.cy),
        point(point),
        pixel(pixel),
        sqrt_information(1.0 / std::sqrt(sigma2)),
        inverse(inverse) {}

  template <typename T>
  bool operator()(const T* quaternion, const T* translation, const T* log_scale, T* residual) const {
    using std::exp;
    const Eigen::Map<const Eigen::Quaternion<T>> q(quaternion);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(translation);
    const Eigen::Matrix<T, 3, 1> x = point.cast<T>();
    Eigen::Matrix<T, 3, 1> p;
    if (inverse) {
      p = (q.conjugate() * (x - t)) * exp(-log_scale[0]);  // cam2_from_cam1 * point_in_cam1
    } else {
      p = (q * x) * exp(log_scale[0]) + t;  // cam1_from_cam2 * point_in_cam2
    }
    if (!(p.z() > T(1e-9))) return false;  // step leaves the camera's front: rejected by Ceres
    residual[0] = T(sqrt_information) * (T(fx) * p.x() / p.z() + T(cx) - T(pixel.x()));
    residual[1] = T(sqrt_information) * (T(fy) * p.y() / p.z() + T(cy) - T(pixel.y()));
    return true;
  }

  double fx, fy, cx, cy;
  Vec3 point;
  Eigen::Vector2d pixel;
  double sqrt_information;
  bool inverse;
};

// Squared error / sigma^2 of one direction; infinity when the point is not in front of the camera.
double chi2_of(const PinholeCamera& camera, const Vec3& point_cam, const Eigen::Vector2d& pixel,
               double sigma2) {
  if (!(point_cam.z() > 0.0)) return std::numeric_limits<double>::infinity();
  return (camera.project(point_cam) - pixel).squaredNorm() / sigma2;
}

struct Sim3Block {
  double quaternion[4];
  double translation[3];
  double log_scale[1];

  explicit Sim3Block(const Sim3& s) {
    const Eigen::Quaterniond& q = s.rotation();
    quaternion[0] = q.x();
    quaternion[1] = q.y();
    quaternion[2] = q.z();
    quaternion[3] = q.w();
    translation[0] = s.translation().x();
    translation[1] = s.translation().y();
    translation[2] = s.translation().z();
    log_scale[0] = std::log(s.scale());
  }
  [[nodiscard]] Sim3 sim3() const {
    const Eigen::Quaterniond q(quaternion[3], quaternion[0], quaternion[1], quaternion[2]);
    return Sim3(q, Vec3(translation[0], translation[1], translation[2]), std::exp(log_scale[0]));
  }
};

// Outlier test of every match at the current estimate: both terms below chi2, both points in front.
void classify(const PinholeCamera& camera1, const PinholeCamera& camera2,
              const std::vector<Sim3Match>& matches, const Sim3& cam1_from_cam2, double chi2,
              std::vector<bool>& active) {
  const Sim3 cam2_from_cam1 = cam1_from_cam2.inverse();
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (!active[i]) continue;
    const Sim3Match& m = matches[i];
    active[i] = chi2_of(camera1, cam1_from_cam2 * m.point_in_cam2, m.pixel1, m.sigma2_1) <= chi2 &&
                chi2_of(camera2, cam2_from_cam1 * m.point_in_cam1, m.pixel2, m.sigma2_2) <= chi2;
  }
}

void solve(const PinholeCamera& camera1, const PinholeCamera& camera2, const std::vector<Sim3Match>& matches,
           const std::vector<bool>& active, const Sim3OptimizationOptions& options, int iterations,
           Sim3Block& block) {
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::HuberLoss loss(std::sqrt(options.chi2));
  using Cost = ceres::AutoDiffCostFunction<Sim3ProjectionError, 2, 4, 3, 1>;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (!active[i]) continue;
    const Sim3Match& m = matches[i];
    problem.AddResidualBlock(
        new Cost(new Sim3ProjectionError(camera1, m.point_in_cam2, m.pixel1, m.sigma2_1, /*inverse=*/false)),
        &loss, block.quaternion, block.translation, block.log_scale);
    problem.AddResidualBlock(
        new Cost(new Sim3ProjectionError(camera2, m.point_in_cam1, m.pixel2, m.sigma2_2, /*inverse=*/true)),
        &loss, block.quaternion, block.translation, block.log_scale);
  }
  if (problem.NumResidualBlocks() == 0) return;
  problem.SetManifold(block.quaternion, new ceres::EigenQuaternionManifold);
  if (options.fix_scale) problem.SetParameterBlockConstant(block.log_scale);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = iterations;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
}

}  // namespace

Sim3OptimizationResult optimize_sim3(const PinholeCamera& camera1, const PinholeCamera& camera2,
                                     const std::vector<Sim3Match>& matches, const std::vector<bool>& use,
                                     const Sim3& initial_cam1_from_cam2,
                                     const Sim3OptimizationOptions& options) {
  assert(use.size() == matches.size());
  Sim3Block block(initial_cam1_from_cam2);
  std::vector<bool> active = use;
  // Matches mapped behind a camera by the initial estimate are outliers; they cannot enter a residual.
  const Sim3 cam2_from_cam1 = initial_cam1_from_cam2.inverse();
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (!active[i]) continue;
    active[i] = (initial_cam1_from_cam2 * matches[i].point_in_cam2).z() > 1e-9 &&
                (cam2_from_cam1 * matches[i].point_in_cam1).z() > 1e-9;
  }

  solve(camera1, camera2, matches, active, options, options.iterations_first, block);
  classify(camera1, camera2, matches, block.sim3(), options.chi2, active);
  if (options.iterations_second > 0) {
    solve(camera1, camera2, matches, active, options, options.iterations_second, block);
  }
  // Final classification of every used match (one dropped in pass 1 may fit the refined estimate).
  active = use;
  classify(camera1, camera2, matches, block.sim3(), options.chi2, active);

  Sim3OptimizationResult result;
  result.cam1_from_cam2 = block.sim3();
  result.inliers = active;
  for (const bool inlier : active) result.num_inliers += inlier ? 1 : 0;
  return result;
}

}  // namespace crowdslam::optim
