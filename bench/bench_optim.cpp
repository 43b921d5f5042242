// Speed of the optimisation back-ends on synthetic problems.
//   bench_optim --benchmark_filter=PoseOptimization   (tracking budget: well under 2 ms for 500 obs)
//   bench_optim --benchmark_filter=LocalBundleAdjustment
//   bench_optim --benchmark_filter=PoseGraph          (essential graph: well under 1 s for 300 / 3000)
//   bench_optim --benchmark_filter=GlobalBundleAdjustment   (global BA after a loop closure)
#include <benchmark/benchmark.h>

#include <algorithm>

#include "../tests/optim/synthetic.h"
#include "../tests/optim/synthetic_loop.h"
#include "crowdslam/optim/bundle_adjustment.h"
#include "crowdslam/optim/pose_graph.h"
#include "crowdslam/optim/pose_optimizer.h"

namespace {

using namespace crowdslam::optim;
using namespace crowdslam::optim::test;

// Args: number of observations. 20% gross outliers, 30% stereo, start 5 cm / 3 deg off.
void BM_PoseOptimization(benchmark::State& state) {
  const PinholeCamera camera = test_camera();
  PoseSceneSpec spec;
  spec.num_points = static_cast<int>(state.range(0));
  spec.outlier_ratio = 0.2;
  spec.stereo_ratio = 0.3;
  const PoseScene scene = make_pose_scene(camera, spec);
  std::mt19937 rng(3);
  const SE3 initial = perturb(scene.truth, 0.05, 3.0 * M_PI / 180.0, rng);
  int iterations = 0;
  for (auto _ : state) {
    const PoseOptimizationResult result = optimize_pose(camera, initial, scene.observations);
    iterations = result.iterations;
    benchmark::DoNotOptimize(result.cam_from_world);
  }
  state.counters["lm_iterations"] = iterations;
}
BENCHMARK(BM_PoseOptimization)->Arg(200)->Arg(500)->Arg(1500)->Unit(benchmark::kMicrosecond);

// Args: keyframes, points, linear solver (0 Ceres sparse Schur, 1 Ceres dense Schur, 2 own Schur LM). Two
// fixed keyframes, 20 outliers.
void BM_LocalBundleAdjustment(benchmark::State& state) {
  const PinholeCamera camera = test_camera();
  BaSceneSpec spec;
  spec.num_keyframes = static_cast<int>(state.range(0));
  spec.num_points = static_cast<int>(state.range(1));
  const BaScene scene = make_ba_scene(camera, spec);
  BundleAdjustmentOptions options;
  const BaLinearSolver solvers[] = {BaLinearSolver::kSparseSchur, BaLinearSolver::kDenseSchur,
                                    BaLinearSolver::kOwnSchur};
  options.linear_solver = solvers[state.range(2)];
  int iterations = 0;
  double final_cost = 0.0;
  for (auto _ : state) {
    const BundleAdjustmentResult result =
        local_bundle_adjustment(camera, scene.keyframes, scene.points, scene.observations, options);
    iterations = result.iterations;
    final_cost = result.final_cost;
    benchmark::DoNotOptimize(result.points.data());
  }
  state.counters["observations"] = static_cast<double>(scene.observations.size());
  state.counters["iterations"] = iterations;
  state.counters["final_cost"] = final_cost;
  state.counters["sparse_backend"] = ceres_has_sparse_backend() ? 1 : 0;
}
BENCHMARK(BM_LocalBundleAdjustment)
    ->Args({10, 500, 0})
    ->Args({10, 500, 1})
    ->Args({10, 500, 2})
    ->Args({20, 2000, 0})
    ->Args({20, 2000, 1})
    ->Args({20, 2000, 2})
    ->Unit(benchmark::kMillisecond);

// Args: nodes, covisibility neighbours per node (edges ~ nodes * neighbours), scale (0 fixed, 1 free).
// rms_after_m is the least-squares optimum, not zero: the covisibility edges agree with the drifted map,
// so the correction bends the trajectory instead of undoing the drift exactly (as in ORB-SLAM).
void BM_PoseGraph(benchmark::State& state) {
  LoopGraphSpec spec;
  spec.num_poses = static_cast<int>(state.range(0));
  spec.neighbours = static_cast<int>(state.range(1));
  spec.loop_neighbours = 10;  // the neighbourhoods of both loop ends are linked (100 loop edges)
  spec.radius_m = 0.1 * spec.num_poses;
  spec.yaw_bias_rad = 0.05 * M_PI / 180.0;
  spec.scale_drift = state.range(2) == 1 ? 0.002 : 0.0;
  const LoopGraph graph = make_loop_graph(spec);
  PoseGraphOptions options;
  options.fix_scale = state.range(2) == 0;
  PoseGraphResult result;
  for (auto _ : state) {
    result = optimize_pose_graph(graph.nodes, graph.edges, options);
    benchmark::DoNotOptimize(result.nodes.data());
  }
  state.counters["edges"] = static_cast<double>(graph.edges.size());
  state.counters["ceres_iterations"] = result.iterations;
  state.counters["rms_before_m"] = trajectory_error(graph.nodes, graph.truth).rms_m;
  state.counters["rms_after_m"] = trajectory_error(result.nodes, graph.truth).rms_m;
}
BENCHMARK(BM_PoseGraph)
    ->Args({300, 10, 0})
    ->Args({300, 10, 1})
    ->Args({1000, 10, 0})
    ->Unit(benchmark::kMillisecond);

// Global-map BA: keyframes on a circle (radius 3 m) looking outwards at a cylinder wall (radius 8 m,
// 3 m high); each point observed by `views` random keyframes among those that see it. Keyframe 0 fixed.
BaScene make_global_ba_scene(const PinholeCamera& camera, int num_keyframes, int num_points, int views) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  BaScene scene;
  for (int k = 0; k < num_keyframes; ++k) {
    const double angle = 2.0 * M_PI * k / num_keyframes;
    const Vec3 centre(3.0 * std::cos(angle), 0.0, 3.0 * std::sin(angle));
    // Optical axis (camera z) along the outward radius, camera y = world y (down).
    const Vec3 z(std::cos(angle), 0.0, std::sin(angle));
    const Vec3 y = Vec3::UnitY();
    Eigen::Matrix3d world_from_cam;
    world_from_cam << y.cross(z), y, z;
    scene.truth_keyframes.push_back({k, SE3(world_from_cam, centre).inverse(), k == 0});
  }
  std::uniform_int_distribution<int> level(0, 3);
  std::vector<int> seen_by;
  for (int p = 0; static_cast<int>(scene.truth_points.size()) < num_points; ++p) {
    const double angle = 2.0 * M_PI * unit(rng);
    const Vec3 world(8.0 * std::cos(angle), -1.5 + 3.0 * unit(rng), 8.0 * std::sin(angle));
    seen_by.clear();
    for (const BaKeyframe& keyframe : scene.truth_keyframes) {
      const Vec3 p_cam = keyframe.cam_from_world * world;
      if (p_cam.z() > 0.5 && camera.is_in_image(camera.project(p_cam))) seen_by.push_back(keyframe.id);
    }
    if (static_cast<int>(seen_by.size()) < views) continue;
    const int point_id = static_cast<int>(scene.truth_points.size());
    scene.truth_points.push_back({point_id, world});
    std::shuffle(seen_by.begin(), seen_by.end(), rng);
    for (int v = 0; v < views; ++v) {
      const BaKeyframe& keyframe = scene.truth_keyframes[seen_by[v]];
      const Vec3 p_cam = keyframe.cam_from_world * world;
      BaObservation obs;
      obs.keyframe_id = keyframe.id;
      obs.point_id = point_id;
      const double sigma = std::pow(1.2, level(rng));
      obs.inv_sigma2 = 1.0 / (sigma * sigma);
      obs.pixel = camera.project(p_cam) + sigma * Vec2(noise(rng), noise(rng));
      if (unit(rng) < 0.3)
        obs.right_u = camera.right_u(camera.project(p_cam).x(), p_cam.z()) + sigma * noise(rng);
      if (unit(rng) < 0.01) obs.pixel += Vec2(40.0, -30.0);  // gross outliers
      scene.observations.push_back(obs);
    }
  }
  scene.keyframes = scene.truth_keyframes;
  for (BaKeyframe& keyframe : scene.keyframes) {
    if (!keyframe.fixed)
      keyframe.cam_from_world = perturb(keyframe.cam_from_world, 0.02, 0.5 * M_PI / 180.0, rng);
  }
  scene.points = scene.truth_points;
  for (BaPoint& point : scene.points) point.world += 0.03 * Vec3(noise(rng), noise(rng), noise(rng));
  return scene;
}

// Args: keyframes, points, views per point, linear solver (0 auto/sparse, 1 dense), threads.
// ORB-SLAM2 runs 10 iterations of global BA without a robust second pass; here the default schedule.
void BM_GlobalBundleAdjustment(benchmark::State& state) {
  const PinholeCamera camera = test_camera();
  const BaScene scene =
      make_global_ba_scene(camera, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                           static_cast<int>(state.range(2)));
  BundleAdjustmentOptions options;
  options.linear_solver = state.range(3) == 0 ? BaLinearSolver::kAuto : BaLinearSolver::kDenseSchur;
  options.num_threads = static_cast<int>(state.range(4));
  BundleAdjustmentResult result;
  for (auto _ : state) {
    result = local_bundle_adjustment(camera, scene.keyframes, scene.points, scene.observations, options);
    benchmark::DoNotOptimize(result.points.data());
  }
  state.counters["observations"] = static_cast<double>(scene.observations.size());
  state.counters["ceres_iterations"] = result.iterations;
  // Convergence: ~0.5 * (2 mono / 3 stereo dof) per inlier observation at the noise level. (Keyframe
  // positions end ~5 cm from the truth even when started there: this ring is noise-limited.)
  state.counters["final_cost_per_obs"] = result.final_cost / static_cast<double>(scene.observations.size());
  state.counters["outliers"] = static_cast<double>(result.outliers.size());
  state.counters["sparse_backend"] = ceres_has_sparse_backend() ? 1 : 0;
}
BENCHMARK(BM_GlobalBundleAdjustment)
    ->Args({200, 20000, 5, 0, 1})
    ->Args({200, 20000, 5, 0, 2})
    ->Args({200, 20000, 5, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
