// Person detector forward time (Yolo-Fastest 1.1 body and COCO models through OpenCV DNN) at input 160,
// 224 and 320 on a 640x480 bonn_crowd frame, one OpenCV thread (cv::setNumThreads(1), as the detection
// worker runs it beside ORB extraction). The time includes blobFromImage, the forward pass, decoding and
// NMS (DarknetDetector::detect).
//
//   build-*/bench/bench_detector --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "crowdslam/people/darknet_detector.h"
#include "crowdslam/people/model_paths.h"

namespace {

std::filesystem::path shared_dir() {
  const char* env = std::getenv("CROWDSLAM_SHARED");
  return env != nullptr && *env != '\0' ? std::filesystem::path(env)
                                        : std::filesystem::path(CROWDSLAM_DEFAULT_SHARED);
}

const cv::Mat& bonn_frame() {
  // Frame 300 of rgbd_bonn_crowd: people in view.
  static const cv::Mat image =
      cv::imread((shared_dir() / "data/bonn_crowd/rgb/1548339829.89644.jpg").string(), cv::IMREAD_COLOR);
  return image;
}

void run(benchmark::State& state, const std::string& model) {
  cv::setNumThreads(1);
  if (bonn_frame().empty()) {
    state.SkipWithError("bonn_crowd frame not found (set CROWDSLAM_SHARED)");
    return;
  }
  crowdslam::people::DetectorOptions options;
  options.input_size = static_cast<int>(state.range(0));
  std::unique_ptr<crowdslam::people::DarknetDetector> detector;
  try {
    detector = std::make_unique<crowdslam::people::DarknetDetector>(crowdslam::people::resolve_model(model),
                                                                    options);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  std::size_t boxes = 0;
  for (auto _ : state) {
    const auto detections = detector->detect(bonn_frame(), 0);
    boxes = detections.boxes.size();
    benchmark::DoNotOptimize(boxes);
  }
  state.counters["boxes"] = static_cast<double>(boxes);
}

void BM_DetectBody(benchmark::State& state) { run(state, "body"); }
void BM_DetectCoco(benchmark::State& state) { run(state, "coco"); }

BENCHMARK(BM_DetectBody)->Arg(160)->Arg(224)->Arg(320)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DetectCoco)->Arg(160)->Arg(224)->Arg(320)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
