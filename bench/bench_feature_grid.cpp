// The feature grid (map/feature_grid.h): building it for a frame's keypoints, and the area queries the
// matcher makes (radius 15 px around each keypoint, as the local-map search does at level 0).
//
//   build-*/bench/bench_feature_grid --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "crowdslam/map/feature_grid.h"

namespace {

using crowdslam::map::FeatureGrid;

std::vector<cv::KeyPoint> random_keypoints(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> x(0.f, 640.f), y(0.f, 480.f);
  std::uniform_int_distribution<int> level(0, 7);
  std::vector<cv::KeyPoint> keys(static_cast<size_t>(n));
  for (auto& k : keys) {
    k.pt = {x(rng), y(rng)};
    k.octave = level(rng);
  }
  return keys;
}

crowdslam::geometry::ImageBounds vga() {
  crowdslam::geometry::ImageBounds b;
  b.min_x = 0;
  b.min_y = 0;
  b.max_x = 640;
  b.max_y = 480;
  return b;
}

void BM_FeatureGridBuild(benchmark::State& state) {
  const auto keys = random_keypoints(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    FeatureGrid grid(keys, vga());
    benchmark::DoNotOptimize(grid);
  }
}
BENCHMARK(BM_FeatureGridBuild)->Arg(1500)->Unit(benchmark::kMicrosecond);

void BM_FeatureGridQueries(benchmark::State& state) {
  const auto keys = random_keypoints(static_cast<int>(state.range(0)));
  const FeatureGrid grid(keys, vga());
  size_t found = 0;
  for (auto _ : state) {
    for (const auto& k : keys) found += grid.features_in_area(keys, k.pt.x, k.pt.y, 15.f, 0, 3).size();
  }
  benchmark::DoNotOptimize(found);
  state.counters["queries"] = static_cast<double>(keys.size());
}
BENCHMARK(BM_FeatureGridQueries)->Arg(1500)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
