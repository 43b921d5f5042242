#include "crowdslam/optim/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <memory>
#include <string>
#include <unordered_map>

#include "crowdslam/optim/ceres_pose.h"
#include "crowdslam/optim/schur_lm.h"
#include "crowdslam/util/error.h"

namespace crowdslam::optim {

using geometry::PinholeCamera;
using geometry::SE3;
using geometry::Vec2;
using geometry::Vec3;

void BundleAdjustmentOptions::check() const {
  auto fail = [](const std::string& key, double value) {
    return InputError("bundle adjustment: " + key + " is invalid: " + std::to_string(value));
  };
  if (first_pass_iterations < 1) throw fail("first_pass_iterations (must be >= 1)", first_pass_iterations);
  if (second_pass_iterations < 0) throw fail("second_pass_iterations (must be >= 0)", second_pass_iterations);
  if (!(chi2_mono > 0.0)) throw fail("chi2_mono (must be > 0)", chi2_mono);
  if (!(chi2_stereo > 0.0)) throw fail("chi2_stereo (must be > 0)", chi2_stereo);
  if (num_threads < 1) throw fail("num_threads (must be >= 1)", num_threads);
}

bool ceres_has_sparse_backend() {
  return ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ||
         ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::CX_SPARSE) ||
         ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE) ||
         ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::ACCELERATE_SPARSE);
}

namespace {

class AbortCallback final : public ceres::IterationCallback {
 public:
  explicit AbortCallback(const std::atomic<bool>* flag) : flag_(flag) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& /*summary*/) override {
    // TERMINATE_SUCCESSFULLY keeps the last accepted state in the parameter blocks.
    return flag_->load(std::memory_order_relaxed) ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                                  : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::atomic<bool>* flag_;
};

constexpr double kPlaneHuberDelta = 1.0;  // plane residuals are in sigmas: linear beyond one sigma

bool aborted(const std::atomic<bool>* flag) {
  return flag != nullptr && flag->load(std::memory_order_relaxed);
}

// Parameter storage plus, per observation, the indices of its keyframe and point (-1: unknown id).
struct BaState {
  std::vector<PoseBlock> poses;
  std::vector<Vec3> points;
  std::vector<int> obs_keyframe;
  std::vector<int> obs_point;
  std::vector<int> plane_keyframe;  // per plane constraint, as obs_keyframe / obs_point
  std::vector<int> plane_point;
  std::vector<SchurRelativePose> relative;  // state indices; both fixed or an unknown id: left out
};

BaState make_state(const std::vector<BaKeyframe>& keyframes, const std::vector<BaPoint>& points,
                   const std::vector<BaObservation>& observations, const std::vector<BaPlaneConstraint>& planes,
                   const std::vector<BaRelativePose>& relative_poses) {
  BaState state;
  std::unordered_map<int, int> keyframe_index;
  std::unordered_map<int, int> point_index;
  for (std::size_t i = 0; i < keyframes.size(); ++i) {
    const bool inserted = keyframe_index.emplace(keyframes[i].id, static_cast<int>(i)).second;
    assert(inserted && "duplicate keyframe id");
    (void)inserted;
    state.poses.push_back(to_pose_block(keyframes[i].cam_from_world));
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const bool inserted = point_index.emplace(points[i].id, static_cast<int>(i)).second;
    assert(inserted && "duplicate point id");
    (void)inserted;
    state.points.push_back(points[i].world);
  }
  // Ids to state indices; -1 for both when either id is unknown (the residual is skipped).
  auto resolve = [&](int keyframe_id, int point_id, std::vector<int>& keyframe_out, std::vector<int>& point_out) {
    const auto k = keyframe_index.find(keyframe_id);
    const auto p = point_index.find(point_id);
    const bool known = k != keyframe_index.end() && p != point_index.end();
    keyframe_out.push_back(known ? k->second : -1);
    point_out.push_back(known ? p->second : -1);
  };
  for (const BaObservation& obs : observations) resolve(obs.keyframe_id, obs.point_id, state.obs_keyframe, state.obs_point);
  for (const BaPlaneConstraint& plane : planes) {
    resolve(plane.keyframe_id, plane.point_id, state.plane_keyframe, state.plane_point);
  }
  for (const BaRelativePose& edge : relative_poses) {
    const auto a = keyframe_index.find(edge.keyframe_id);
    const auto b = keyframe_index.find(edge.other_id);
    if (a == keyframe_index.end() || b == keyframe_index.end() || a->second == b->second) continue;
    if (keyframes[a->second].fixed && keyframes[b->second].fixed) continue;
    SchurRelativePose r;
    r.pose_a = a->second;
    r.pose_b = b->second;
    r.a_from_b = edge.cam_from_other;
    const double wt = 1.0 / (edge.translation_sigma * edge.translation_sigma);
    const double wr = 1.0 / (edge.rotation_sigma_rad * edge.rotation_sigma_rad);
    r.weight << wt, wt, wt, wr, wr, wr;
    state.relative.push_back(r);
  }
  return state;
}

ceres::LinearSolverType linear_solver_type(BaLinearSolver choice) {
  if (choice == BaLinearSolver::kDenseSchur || !ceres_has_sparse_backend()) return ceres::DENSE_SCHUR;
  return ceres::SPARSE_SCHUR;
}

class BaSolver {
 public:
  BaSolver(const PinholeCamera& camera, const std::vector<BaKeyframe>& keyframes,
           const std::vector<BaObservation>& observations, const std::vector<BaPlaneConstraint>& planes,
           const BundleAdjustmentOptions& options, BaState& state)
      : camera_(camera),
        keyframes_(keyframes),
        observations_(observations),
        planes_(planes),
        options_(options),
        state_(state) {}

  [[nodiscard]] bool is_stereo(const BaObservation& obs) const { return obs.is_stereo() && camera_.bf > 0.0; }

  // Outlier test of one observation at the current state.
  [[nodiscard]] bool is_outlier(std::size_t i) const {
    const BaObservation& obs = observations_[i];
    const SE3 pose = from_pose_block(state_.poses[state_.obs_keyframe[i]]);
    const Vec3 p_cam = pose * state_.points[state_.obs_point[i]];
    if (!(p_cam.z() > 0.0)) return true;
    const Vec2 predicted = camera_.project(p_cam);
    double error2 = (predicted - obs.pixel).squaredNorm();
    if (is_stereo(obs)) {
      const double du = camera_.right_u(predicted.x(), p_cam.z()) - obs.right_u;
      error2 += du * du;
    }
    return obs.inv_sigma2 * error2 > (is_stereo(obs) ? options_.chi2_stereo : options_.chi2_mono);
  }

  struct PassSummary {
    double initial_cost = 0.0;
    double final_cost = 0.0;
    int iterations = 0;
  };

  // One solve over the observations with active[i] set.
  PassSummary solve(const std::vector<bool>& active, bool robust, int iterations,
                    const std::atomic<bool>* abort_flag) {
    if (use_own_solver()) return solve_own(active, robust, iterations, abort_flag);
    const ceres::Solver::Summary summary = solve_ceres(active, robust, iterations, abort_flag);
    return {summary.initial_cost, summary.final_cost,
            summary.num_successful_steps + summary.num_unsuccessful_steps};
  }

 private:
  [[nodiscard]] bool use_own_solver() const {
    if (options_.linear_solver == BaLinearSolver::kOwnSchur) return true;
    if (options_.linear_solver != BaLinearSolver::kAuto) return false;
    const auto free =
        std::count_if(keyframes_.begin(), keyframes_.end(), [](const BaKeyframe& k) { return !k.fixed; });
    return free <= kOwnSchurMaxFreePoses;
  }

  PassSummary solve_own(const std::vector<bool>& active, bool robust, int iterations,
                        const std::atomic<bool>* abort_flag) {
    std::vector<SE3> poses;
    std::vector<bool> fixed;
    poses.reserve(state_.poses.size());
    for (std::size_t k = 0; k < state_.poses.size(); ++k) {
      poses.push_back(from_pose_block(state_.poses[k]));
      fixed.push_back(keyframes_[k].fixed);
    }
    std::vector<SchurObservation> observations;
    observations.reserve(observations_.size());
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      if (!active[i]) continue;
      const BaObservation& obs = observations_[i];
      SchurObservation o;
      o.pose = state_.obs_keyframe[i];
      o.point = state_.obs_point[i];
      o.pixel = obs.pixel;
      o.stereo = is_stereo(obs);
      o.right_u = obs.right_u;
      o.sqrt_information = std::sqrt(obs.inv_sigma2);
      o.huber_delta = robust ? std::sqrt(o.stereo ? options_.chi2_stereo : options_.chi2_mono) : 0.0;
      observations.push_back(o);
    }
    for (std::size_t i = 0; i < planes_.size(); ++i) {
      if (state_.plane_keyframe[i] < 0) continue;
      SchurObservation o;
      o.pose = state_.plane_keyframe[i];
      o.point = state_.plane_point[i];
      o.plane = true;
      o.normal = planes_[i].normal_cam;
      o.distance = planes_[i].distance;
      o.sqrt_information = 1.0 / planes_[i].sigma;
      o.huber_delta = kPlaneHuberDelta;
      observations.push_back(o);
    }
    const SchurLmSummary summary = solve_schur_lm(camera_, poses, fixed, state_.points, observations, iterations,
                                                  abort_flag, state_.relative);
    for (std::size_t k = 0; k < poses.size(); ++k) {
      if (!fixed[k]) state_.poses[k] = to_pose_block(poses[k]);
    }
    return {summary.initial_cost, summary.final_cost, summary.successful_steps + summary.unsuccessful_steps};
  }

  ceres::Solver::Summary solve_ceres(const std::vector<bool>& active, bool robust, int iterations,
                                     const std::atomic<bool>* abort_flag) {
    ceres::Problem::Options problem_options;
    problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    const CostCamera cost_camera = CostCamera::from(camera_);
    ceres::HuberLoss mono_loss(std::sqrt(options_.chi2_mono));
    ceres::HuberLoss stereo_loss(std::sqrt(options_.chi2_stereo));
    std::vector<bool> pose_used(state_.poses.size(), false);
    std::vector<bool> point_used(state_.points.size(), false);
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      if (!active[i]) continue;
      const BaObservation& obs = observations_[i];
      const int k = state_.obs_keyframe[i];
      const int p = state_.obs_point[i];
      double* pose = state_.poses[k].data();
      double* point = state_.points[p].data();
      if (!pose_used[k]) {
        problem.AddParameterBlock(pose, 7, &manifold_);
        if (keyframes_[k].fixed) problem.SetParameterBlockConstant(pose);
        pose_used[k] = true;
      }
      point_used[p] = true;
      if (is_stereo(obs)) {
        problem.AddResidualBlock(
            new StereoReprojectionCost(cost_camera, obs.pixel, obs.right_u, obs.inv_sigma2),
            robust ? &stereo_loss : nullptr, pose, point);
      } else {
        problem.AddResidualBlock(new MonoReprojectionCost(cost_camera, obs.pixel, obs.inv_sigma2),
                                 robust ? &mono_loss : nullptr, pose, point);
      }
    }
    ceres::HuberLoss plane_loss(kPlaneHuberDelta);
    for (std::size_t i = 0; i < planes_.size(); ++i) {
      const int k = state_.plane_keyframe[i];
      const int p = state_.plane_point[i];
      if (k < 0 || !point_used[p]) continue;  // a plane alone does not make a point optimisable
      double* pose = state_.poses[k].data();
      if (!pose_used[k]) {
        problem.AddParameterBlock(pose, 7, &manifold_);
        if (keyframes_[k].fixed) problem.SetParameterBlockConstant(pose);
        pose_used[k] = true;
      }
      problem.AddResidualBlock(new PlaneDistanceCost(planes_[i].normal_cam, planes_[i].distance, planes_[i].sigma),
                               &plane_loss, pose, state_.points[p].data());
    }
    for (const SchurRelativePose& edge : state_.relative) {
      for (const int k : {edge.pose_a, edge.pose_b}) {
        if (pose_used[k]) continue;
        problem.AddParameterBlock(state_.poses[k].data(), 7, &manifold_);
        if (keyframes_[k].fixed) problem.SetParameterBlockConstant(state_.poses[k].data());
        pose_used[k] = true;
      }
      problem.AddResidualBlock(new RelativePoseCost(edge.a_from_b, edge.weight), nullptr,
                               state_.poses[edge.pose_a].data(), state_.poses[edge.pose_b].data());
    }
    ceres::Solver::Summary summary;
    if (problem.NumResidualBlocks() == 0) return summary;

    // Points first (eliminated by the Schur complement), then poses.
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (std::size_t p = 0; p < state_.points.size(); ++p) {
      if (point_used[p]) ordering->AddElementToGroup(state_.points[p].data(), 0);
    }
    for (std::size_t k = 0; k < state_.poses.size(); ++k) {
      if (pose_used[k]) ordering->AddElementToGroup(state_.poses[k].data(), 1);
    }
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = linear_solver_type(options_.linear_solver);
    solver_options.linear_solver_ordering = ordering;
    solver_options.max_num_iterations = iterations;
    solver_options.num_threads = options_.num_threads;
    solver_options.logging_type = ceres::SILENT;
    AbortCallback callback(abort_flag);
    if (abort_flag != nullptr) solver_options.callbacks.push_back(&callback);
    ceres::Solve(solver_options, &problem, &summary);
    return summary;
  }

  const PinholeCamera& camera_;
  const std::vector<BaKeyframe>& keyframes_;
  const std::vector<BaObservation>& observations_;
  const std::vector<BaPlaneConstraint>& planes_;
  const BundleAdjustmentOptions& options_;
  BaState& state_;
  Se3Manifold manifold_;
};

}  // namespace

BundleAdjustmentResult local_bundle_adjustment(const PinholeCamera& camera,
                                               const std::vector<BaKeyframe>& keyframes,
                                               const std::vector<BaPoint>& points,
                                               const std::vector<BaObservation>& observations,
                                               const BundleAdjustmentOptions& options,
                                               const std::atomic<bool>* abort_flag,
                                               const std::vector<BaPlaneConstraint>& planes,
                                               const std::vector<BaRelativePose>& relative_poses) {
  BundleAdjustmentResult result;
  result.keyframes = keyframes;
  result.points = points;
  if (aborted(abort_flag)) {
    result.aborted = true;
    return result;
  }
  BaState state = make_state(keyframes, points, observations, planes, relative_poses);
  BaSolver solver(camera, keyframes, observations, planes, options, state);

  std::vector<bool> active(observations.size());
  for (std::size_t i = 0; i < observations.size(); ++i) active[i] = state.obs_keyframe[i] >= 0;

  const auto first = solver.solve(active, /*robust=*/true, options.first_pass_iterations, abort_flag);
  result.iterations += first.iterations;
  result.initial_cost = first.initial_cost;
  result.final_cost = first.final_cost;
  result.aborted = aborted(abort_flag);

  if (!result.aborted && options.second_pass_iterations > 0) {
    for (std::size_t i = 0; i < observations.size(); ++i) active[i] = active[i] && !solver.is_outlier(i);
    const auto second = solver.solve(active, /*robust=*/false, options.second_pass_iterations, abort_flag);
    result.iterations += second.iterations;
    result.final_cost = second.final_cost;
    result.aborted = aborted(abort_flag);
  }

  for (std::size_t i = 0; i < observations.size(); ++i) {
    if (state.obs_keyframe[i] >= 0 && solver.is_outlier(i)) result.outliers.push_back(i);
  }
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    if (!keyframes[k].fixed) result.keyframes[k].cam_from_world = from_pose_block(state.poses[k]);
  }
  for (std::size_t p = 0; p < points.size(); ++p) result.points[p].world = state.points[p];
  return result;
}

}  // namespace crowdslam::optim
