// Speed of the ORB extractor (target: median <= 10 ms for 1000 features on a 640x480 Bonn frame, one
// thread), of its two steps apart (prepare, extract from the prepared image), and of the Hamming distance.
//
//   build-*/bench/bench_orb_extractor --benchmark_repetitions=5
//
// OpenCV's own thread pool is switched off (cv::setNumThreads(1)) so that the numbers are single-thread.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/feature/orb_extractor.h"

namespace {

using crowdslam::feature::ORBExtractor;

std::filesystem::path shared_dir() {
  const char* env = std::getenv("CROWDSLAM_SHARED");
  return env != nullptr && *env != '\0' ? std::filesystem::path(env)
                                        : std::filesystem::path(CROWDSLAM_DEFAULT_SHARED);
}

const cv::Mat& bonn_frame_gray() {
  static const cv::Mat gray = [] {
    const auto path = shared_dir() / "data/bonn_crowd/rgb/1548339819.87426.jpg";
    return cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  }();
  return gray;
}

// The Bonn frame with OpenCV's pool off; empty, and the benchmark marked skipped, without ../shared.
const cv::Mat& single_thread_bonn_frame(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat& gray = bonn_frame_gray();
  if (gray.empty()) state.SkipWithError("Bonn frame not found (set CROWDSLAM_SHARED)");
  return gray;
}

void BM_OrbExtract(benchmark::State& state) {
  const cv::Mat& gray = single_thread_bonn_frame(state);
  if (gray.empty()) return;
  ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  const int budget = static_cast<int>(state.range(0));
  for (auto _ : state) {
    extractor.extract(gray, budget, keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(keypoints.size());
}
double percentile(std::vector<double> values, double fraction) {
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1) + 0.5)];
}

BENCHMARK(BM_OrbExtract)
    ->Arg(1000)
    ->Arg(2000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("p95", [](const std::vector<double>& v) { return percentile(v, 0.95); });

// Per-frame latency over the first 100 frames of the sequence (content varies: people, blur), with the
// per-frame median and 95th percentile as counters.
void BM_OrbExtractSequence(benchmark::State& state) {
  cv::setNumThreads(1);
  std::vector<cv::Mat> frames;
  const auto folder = shared_dir() / "data/bonn_crowd/rgb";
  std::vector<std::filesystem::path> paths;
  if (std::filesystem::is_directory(folder)) {
    for (const auto& entry : std::filesystem::directory_iterator(folder)) paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  for (std::size_t i = 0; i < paths.size() && frames.size() < 100; ++i) {
    frames.push_back(cv::imread(paths[i].string(), cv::IMREAD_GRAYSCALE));
  }
  if (frames.empty()) {
    state.SkipWithError("Bonn frames not found (set CROWDSLAM_SHARED)");
    return;
  }
  ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<double> times_ms;
  std::size_t next = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    extractor.extract(frames[next], 1000, keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
    times_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    next = (next + 1) % frames.size();
  }
  state.counters["frame_p50_ms"] = percentile(times_ms, 0.5);
  state.counters["frame_p95_ms"] = percentile(times_ms, 0.95);
}
BENCHMARK(BM_OrbExtractSequence)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(500);

// The two steps apart: prepare() (pyramid, FAST, blur: the reader thread's share in `crowdslam run`) and
// extract() from the prepared image (distribution, orientation, BRIEF: what is left on the tracking
// thread), at the budgets of Bonn.yaml (1000) and of FNU's largest factor (2200).
void BM_OrbPrepare(benchmark::State& state) {
  const cv::Mat& gray = single_thread_bonn_frame(state);
  if (gray.empty()) return;
  ORBExtractor extractor;
  crowdslam::feature::PreparedImage prepared;
  for (auto _ : state) {
    extractor.prepare(gray, prepared);
    benchmark::DoNotOptimize(prepared.blurred.back().data);
  }
}
BENCHMARK(BM_OrbPrepare)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_OrbExtractPrepared(benchmark::State& state) {
  const cv::Mat& gray = single_thread_bonn_frame(state);
  if (gray.empty()) return;
  ORBExtractor extractor;
  crowdslam::feature::PreparedImage prepared;
  extractor.prepare(gray, prepared);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  const int budget = static_cast<int>(state.range(0));
  for (auto _ : state) {
    extractor.extract(prepared, budget, keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(keypoints.size());
}
BENCHMARK(BM_OrbExtractPrepared)->Arg(1000)->Arg(2200)->Unit(benchmark::kMillisecond)->UseRealTime();

// For comparison: OpenCV's ORB on the same frame and budget (no grid, no quadtree).
void BM_CvOrbDetectAndCompute(benchmark::State& state) {
  const cv::Mat& gray = single_thread_bonn_frame(state);
  if (gray.empty()) return;
  const auto orb = cv::ORB::create(static_cast<int>(state.range(0)), 1.2f, 8, 19, 0, 2, cv::ORB::FAST_SCORE);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    orb->detectAndCompute(gray, cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
}
BENCHMARK(BM_CvOrbDetectAndCompute)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime();

// The plain builtin, for comparison: without -mpopcnt GCC turns it into a call to libgcc's __popcountdi2.
int hamming_builtin(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (int word = 0; word < 4; ++word) {
    std::uint64_t wa = 0;
    std::uint64_t wb = 0;
    std::memcpy(&wa, a + 8 * word, sizeof wa);
    std::memcpy(&wb, b + 8 * word, sizeof wb);
    distance += __builtin_popcountll(wa ^ wb);
  }
  return distance;
}

// All pairs between two sets of 1000 descriptors (one million distances).
template <int (*Distance)(const std::uint8_t*, const std::uint8_t*)>
void BM_HammingDistance(benchmark::State& state) {
  constexpr int kCount = 1000;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<std::uint8_t> a(kCount * 32);
  std::vector<std::uint8_t> b(kCount * 32);
  for (auto& value : a) value = static_cast<std::uint8_t>(byte(rng));
  for (auto& value : b) value = static_cast<std::uint8_t>(byte(rng));
  for (auto _ : state) {
    long sum = 0;
    for (int i = 0; i < kCount; ++i) {
      for (int j = 0; j < kCount; ++j) {
        sum += Distance(&a[i * 32], &b[j * 32]);
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * kCount * kCount);
}
BENCHMARK_TEMPLATE(BM_HammingDistance, crowdslam::feature::hamming_distance)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_HammingDistance, hamming_builtin)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
