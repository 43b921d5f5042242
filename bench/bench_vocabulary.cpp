// Speed of the ORB vocabulary (bow/vocabulary.h).
//   bench_vocabulary --benchmark_filter=LoadBinary   target: a 1M-word vocabulary (k = 10, L = 6) < 0.5 s
//   bench_vocabulary --benchmark_filter=LoadDefault  the default vocabulary (bow/vocabulary_path.h;
//                                                    scripts/build_vocabulary.sh), target < 0.5 s
//   bench_vocabulary --benchmark_filter=Transform    1000 descriptors -> BoW + direct index
//   bench_vocabulary --benchmark_filter=ImportText   DBoW2 text import (k = 10, L = 5, 111k nodes)
// The 1M-word file is written here in the documented binary format (full tree, random descriptors);
// the text file by the DBoW2 layout. Both go to the system temp directory and are removed at exit.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/bow/vocabulary_path.h"

namespace {

using crowdslam::bow::BowVector;
using crowdslam::bow::FeatureVector;
using crowdslam::bow::Vocabulary;

// Full tree of branching k and depth L in breadth-first order: node i > 0 has parent (i - 1) / k.
std::size_t full_tree_nodes(int k, int levels) {
  std::size_t total = 0;
  std::size_t width = 1;
  for (int l = 0; l <= levels; ++l, width *= k) total += width;
  return total;
}

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

const std::string& binary_file() {
  static const std::string path = [] {
    const int k = 10;
    const int levels = 6;
    const std::size_t n = full_tree_nodes(k, levels);
    const std::size_t inner = full_tree_nodes(k, levels - 1);
    std::mt19937 rng(1);
    std::string out;
    out.reserve(32 + 44 * n);
    out.append("CSLMVOC1", 8);
    put<std::uint32_t>(out, 1);
    put<std::uint32_t>(out, 32);
    put<std::uint32_t>(out, k);
    put<std::uint32_t>(out, levels);
    put<std::uint64_t>(out, n);
    for (std::size_t i = 0; i < n; ++i) {
      put<std::uint32_t>(out, i == 0 ? 0xFFFFFFFFu : static_cast<std::uint32_t>((i - 1) / k));
      for (int b = 0; b < 8; ++b) put<std::uint32_t>(out, rng());
      put<float>(out, i < inner ? 0.0f : 1.0f);
      put<std::uint32_t>(out, i < inner ? 0xFFFFFFFFu : static_cast<std::uint32_t>(i - inner));
    }
    const auto file = std::filesystem::temp_directory_path() / "crowdslam_bench_vocabulary.bin";
    std::ofstream(file, std::ios::binary).write(out.data(), static_cast<std::streamsize>(out.size()));
    return file.string();
  }();
  return path;
}

const std::string& text_file() {
  static const std::string path = [] {
    const int k = 10;
    const int levels = 5;
    const std::size_t n = full_tree_nodes(k, levels);
    const std::size_t inner = full_tree_nodes(k, levels - 1);
    std::mt19937 rng(2);
    const auto file = std::filesystem::temp_directory_path() / "crowdslam_bench_vocabulary.txt";
    std::ofstream out(file);
    out << k << ' ' << levels << " 0 0\n";
    for (std::size_t i = 1; i < n; ++i) {
      out << (i - 1) / k << ' ' << (i < inner ? 0 : 1);
      for (int b = 0; b < 32; ++b) out << ' ' << (rng() & 0xFF);
      out << ' ' << (i < inner ? "0" : "0.5") << '\n';
    }
    return file.string();
  }();
  return path;
}

void BM_LoadBinary(benchmark::State& state) {
  const std::string& path = binary_file();
  std::size_t words = 0;
  for (auto _ : state) {
    const Vocabulary voc = Vocabulary::load(path);
    words = voc.num_words();
    benchmark::DoNotOptimize(words);
  }
  state.counters["words"] = static_cast<double>(words);
}
BENCHMARK(BM_LoadBinary)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_LoadDefault(benchmark::State& state) {
  const std::string path = crowdslam::bow::default_vocabulary_path();
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("default vocabulary " + path + " missing (scripts/build_vocabulary.sh)").c_str());
    return;
  }
  std::size_t words = 0;
  for (auto _ : state) {
    const Vocabulary voc = Vocabulary::read(path);
    words = voc.num_words();
    benchmark::DoNotOptimize(words);
  }
  state.counters["words"] = static_cast<double>(words);
}
BENCHMARK(BM_LoadDefault)->Unit(benchmark::kMillisecond);

void BM_Transform(benchmark::State& state) {
  static const Vocabulary voc = Vocabulary::load(binary_file());
  cv::Mat descriptors(1000, 32, CV_8UC1);
  cv::randu(descriptors, 0, 256);
  BowVector bow;
  FeatureVector features;
  for (auto _ : state) {
    voc.transform(descriptors, bow, features);
    benchmark::DoNotOptimize(bow.size());
  }
}
BENCHMARK(BM_Transform)->Unit(benchmark::kMillisecond);

void BM_ImportText(benchmark::State& state) {
  const std::string& path = text_file();
  for (auto _ : state) {
    const Vocabulary voc = Vocabulary::import_dbow2_text(path);
    benchmark::DoNotOptimize(voc.num_words());
  }
}
BENCHMARK(BM_ImportText)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::error_code ec;
  std::filesystem::remove(std::filesystem::temp_directory_path() / "crowdslam_bench_vocabulary.bin", ec);
  std::filesystem::remove(std::filesystem::temp_directory_path() / "crowdslam_bench_vocabulary.txt", ec);
  return 0;
}
