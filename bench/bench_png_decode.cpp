// PNG decoding of dataset images, one thread: cv::imdecode against the fast decoder (io/png_decode.h) on
// the same bytes in memory, and the whole read_depth_image / read_colour_image (file read, chunk CRCs,
// decode). Bonn depth maps (640x480, 16-bit grey, about half the rows Paeth-filtered) and KITTI grey
// frames (1226x370, 8-bit).
//
//   build-*/bench/bench_png_decode --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "crowdslam/io/image_check.h"
#include "crowdslam/io/png_decode.h"

namespace {

namespace fs = std::filesystem;

fs::path shared_dir() {
  const char* env = std::getenv("CROWDSLAM_SHARED");
  return env != nullptr && *env != '\0' ? fs::path(env) : fs::path(CROWDSLAM_DEFAULT_SHARED);
}

struct Files {
  std::vector<std::string> paths;
  std::vector<std::vector<unsigned char>> bytes;
};

// The first 20 PNGs of a shared folder (sorted), read once.
Files load(const std::string& folder) {
  Files files;
  const fs::path dir = shared_dir() / "data" / folder;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().extension() == ".png") files.paths.push_back(entry.path().string());
  std::sort(files.paths.begin(), files.paths.end());
  files.paths.resize(std::min<std::size_t>(files.paths.size(), 20));
  for (const std::string& path : files.paths) {
    std::ifstream in(path, std::ios::binary);
    files.bytes.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>{});
  }
  return files;
}

const Files& bonn_depth() {
  static const Files files = load("bonn_crowd/depth");
  return files;
}

const Files& kitti_grey() {
  static const Files files = load("kitti07_head/image_0");
  return files;
}

enum class Decoder { kImdecode, kFast, kReadImage };

void run(benchmark::State& state, const Files& files, int flags, Decoder decoder) {
  cv::setNumThreads(1);
  if (files.paths.empty()) {
    state.SkipWithError("shared dataset not found (set CROWDSLAM_SHARED)");
    return;
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % files.paths.size();
    cv::Mat image;
    if (decoder == Decoder::kImdecode) {
      image = cv::imdecode(files.bytes[k], flags);
    } else if (decoder == Decoder::kFast) {
      image = crowdslam::io::decode_png(files.bytes[k].data(), files.bytes[k].size(), flags, files.paths[k]);
    } else {
      image = flags == cv::IMREAD_UNCHANGED ? crowdslam::io::read_depth_image(files.paths[k])
                                            : crowdslam::io::read_colour_image(files.paths[k]);
    }
    if (image.empty()) {
      state.SkipWithError("not decoded");
      break;
    }
    benchmark::DoNotOptimize(image.data);
  }
}

void BM_BonnDepthImdecode(benchmark::State& s) {
  run(s, bonn_depth(), cv::IMREAD_UNCHANGED, Decoder::kImdecode);
}
void BM_BonnDepthFast(benchmark::State& s) { run(s, bonn_depth(), cv::IMREAD_UNCHANGED, Decoder::kFast); }
void BM_BonnDepthReadDepthImage(benchmark::State& s) {
  run(s, bonn_depth(), cv::IMREAD_UNCHANGED, Decoder::kReadImage);
}
void BM_KittiGreyImdecode(benchmark::State& s) {
  run(s, kitti_grey(), cv::IMREAD_ANYCOLOR, Decoder::kImdecode);
}
void BM_KittiGreyFast(benchmark::State& s) { run(s, kitti_grey(), cv::IMREAD_ANYCOLOR, Decoder::kFast); }
void BM_KittiGreyReadColourImage(benchmark::State& s) {
  run(s, kitti_grey(), cv::IMREAD_ANYCOLOR, Decoder::kReadImage);
}

BENCHMARK(BM_BonnDepthImdecode)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BonnDepthFast)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BonnDepthReadDepthImage)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KittiGreyImdecode)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KittiGreyFast)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KittiGreyReadColourImage)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
