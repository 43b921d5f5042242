// Speed of the optimisation back-ends on synthetic problems.
//   bench_optim --benchmark_filter=PoseOptimization   (tracking budget: well under 2 ms for 500 obs)
//   bench_optim --benchmark_filter=LocalBundleAdjustment
#include <benchmark/benchmark.h>

#include "../tests/optim/synthetic.h"
#include "crowdslam/optim/bundle_adjustment.h"
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

// Args: keyframes, points, linear solver (0 auto/sparse, 1 dense). Two fixed keyframes, 20 outliers.
void BM_LocalBundleAdjustment(benchmark::State& state) {
  const PinholeCamera camera = test_camera();
  BaSceneSpec spec;
  spec.num_keyframes = static_cast<int>(state.range(0));
  spec.num_points = static_cast<int>(state.range(1));
  const BaScene scene = make_ba_scene(camera, spec);
  BundleAdjustmentOptions options;
  options.linear_solver = state.range(2) == 0 ? BaLinearSolver::kAuto : BaLinearSolver::kDenseSchur;
  int iterations = 0;
  for (auto _ : state) {
    const BundleAdjustmentResult result =
        local_bundle_adjustment(camera, scene.keyframes, scene.points, scene.observations, options);
    iterations = result.iterations;
    benchmark::DoNotOptimize(result.points.data());
  }
  state.counters["observations"] = static_cast<double>(scene.observations.size());
  state.counters["ceres_iterations"] = iterations;
  state.counters["sparse_backend"] = ceres_has_sparse_backend() ? 1 : 0;
}
BENCHMARK(BM_LocalBundleAdjustment)
    ->Args({10, 500, 0})
    ->Args({10, 500, 1})
    ->Args({20, 2000, 0})
    ->Args({20, 2000, 1})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
