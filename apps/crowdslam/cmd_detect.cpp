// `crowdslam detect`: run the person detector over a sequence and write MOT-format boxes.
// `crowdslam detect-eval`: precision, recall, MODA, MODP of MOT-format detections against ground truth.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/people/darknet_detector.h"
#include "crowdslam/people/detection_metrics.h"
#include "crowdslam/people/model_paths.h"
#include "crowdslam/people/mot_format.h"
#include "crowdslam/people/mot_sequence.h"

namespace crowdslam::app {
namespace {

constexpr int kMaxInputSize = 2048;  // as Detector.input_size in the settings
constexpr int kMaxPersonClass = 9999;
constexpr int kMaxThreads = 64;
constexpr std::size_t kMaxFrames = 1000000000;

struct DetectArgs {
  std::string settings;
  std::string dataset;
  std::string out;
  std::string model = "body";
  people::DetectorOptions options;
  bool raw = false;
  std::size_t max_frames = 0;
  CLI::App* app = nullptr;  // to see which options were given
};

struct DetectEvalArgs {
  std::string ground_truth;
  std::string detections;
  people::DetectionEvalOptions options;
};

bool given(const CLI::App& app, const std::string& option) { return app.count(option) > 0; }

// Settings first (Detector.* keys), then the command-line options that were given explicitly.
people::ModelFiles configure(DetectArgs& args) {
  people::ModelFiles model = people::resolve_model(args.model);
  if (!args.settings.empty()) {
    const io::DetectorSettings d = io::load_settings(args.settings, io::SensorKind::kMonocular).detector;
    const CLI::App& app = *args.app;
    if (!given(app, "--input-size")) args.options.input_size = d.input_size;
    if (!given(app, "--confidence")) args.options.confidence = d.confidence;
    if (!given(app, "--nms")) args.options.nms = d.nms;
    if (!given(app, "--person-class")) args.options.person_class = d.person_class;
    if (!given(app, "--raw")) args.raw = d.filter_before_nms;
    if (!given(app, "--model") && !d.model_cfg.empty())
      model = {d.model_cfg, d.model_weights, d.person_class};
  }
  args.options.check();
  return model;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

void run_detect(DetectArgs& args, const GlobalOptions& global) {
  const people::ModelFiles model = configure(args);
  auto source = people::open_detection_source(args.dataset);
  people::DarknetDetector detector(model, args.options);
  std::vector<people::FrameBoxes> frames;
  std::vector<double> times_ms;
  std::size_t boxes = 0;
  while (auto frame = source->next()) {
    if (args.max_frames > 0 && frames.size() >= args.max_frames) break;
    people::Detections d = detector.detect(frame->images.colour, frame->info.index);
    times_ms.push_back(d.time_ms);
    boxes += (args.raw ? d.raw : d.boxes).size();
    frames.push_back({frame->info.index, args.raw ? std::move(d.raw) : std::move(d.boxes)});
    if (frames.size() % 100 == 0) spdlog::info("{} frames", frames.size());
  }
  people::write_mot_detections(args.out, frames);
  double mean_ms = 0.0;
  for (double t : times_ms) mean_ms += t;
  if (!times_ms.empty()) mean_ms /= static_cast<double>(times_ms.size());
  if (global.json) {
    print_json({{"dataset", args.dataset},
                {"out", args.out},
                {"detector", detector.name()},
                {"model_config", model.config},
                {"input_size", args.options.input_size},
                {"confidence", args.options.confidence},
                {"nms", args.options.nms},
                {"before_nms", args.raw},
                {"frames", frames.size()},
                {"boxes", boxes},
                {"mean_time_ms", mean_ms},
                {"median_time_ms", median(times_ms)}});
    return;
  }
  std::printf("detector   %s (%s)\n", detector.name().c_str(), args.raw ? "boxes before NMS" : "after NMS");
  std::printf("frames     %zu\n", frames.size());
  std::printf("boxes      %zu\n", boxes);
  std::printf("time_ms    mean %.3f median %.3f\n", mean_ms, median(times_ms));
  std::printf("written    %s\n", args.out.c_str());
  std::fflush(stdout);
}

nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nullptr; }

std::string percent(double value) {
  if (!std::isfinite(value)) return "n/a";
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f %%", 100.0 * value);
  return text;
}

void run_detect_eval(const DetectEvalArgs& args, const GlobalOptions& global) {
  args.options.check();
  const people::MotFile gt = people::read_mot_file(args.ground_truth, true);
  const people::MotFile det = people::read_mot_file(args.detections);
  const people::DetectionCounts c = people::evaluate_detections(gt, det, args.options);
  const char* format = people::to_string(people::ground_truth_format(gt));
  if (global.json) {
    print_json({{"ground_truth", args.ground_truth},
                {"detections", args.detections},
                {"ground_truth_format", format},
                {"iou_threshold", args.options.iou_threshold},
                {"min_visibility", args.options.min_visibility},
                {"frames", c.frames},
                {"ground_truth_boxes", c.ground_truth},
                {"ignored_ground_truth_boxes", c.ignored_ground_truth},
                {"detection_boxes", c.detections},
                {"discarded_detections", c.discarded_detections},
                {"tp", c.true_positives},
                {"fp", c.false_positives},
                {"fn", c.false_negatives},
                {"precision", number_or_null(c.precision())},
                {"recall", number_or_null(c.recall())},
                {"moda", number_or_null(c.moda())},
                {"modp", number_or_null(c.modp())}});
    return;
  }
  std::printf("ground truth   %s (%s, %zu boxes, %zu ignored)\n", args.ground_truth.c_str(), format,
              c.ground_truth, c.ignored_ground_truth);
  std::printf("detections     %s (%zu boxes, %zu on ignored ground truth)\n", args.detections.c_str(),
              c.detections, c.discarded_detections);
  std::printf("frames         %zu\n", c.frames);
  std::printf("TP %zu  FP %zu  FN %zu  (IoU >= %g)\n", c.true_positives, c.false_positives, c.false_negatives,
              args.options.iou_threshold);
  std::printf("precision      %s\n", percent(c.precision()).c_str());
  std::printf("recall         %s\n", percent(c.recall()).c_str());
  std::printf("MODA           %s\n", percent(c.moda()).c_str());
  std::printf("MODP           %s\n", percent(c.modp()).c_str());
  std::fflush(stdout);
}

}  // namespace

void add_detect_command(CLI::App& app, const GlobalOptions& global) {
  auto args = std::make_shared<DetectArgs>();
  CLI::App* detect = app.add_subcommand("detect", "Run the person detector over a sequence, write MOT boxes");
  args->app = detect;
  detect->add_option("--settings", args->settings, "Settings file (Detector.* keys)");
  detect
      ->add_option("--dataset", args->dataset,
                   "Sequence: MOT folder (img1/ + seqinfo.ini), TUM/Bonn, EuRoC, KITTI, image folder, video")
      ->required();
  detect->add_option("--out", args->out, "Output detections, MOT format frame,-1,x,y,w,h,conf,-1,-1,-1")
      ->required();
  detect
      ->add_option("--model", args->model, "body, coco, a Darknet .cfg (.weights beside it) or an .onnx file")
      ->capture_default_str();
  // Every numeric option is bounded here, so a bad value is a clear CLI error (e.g. --threads 100000 used
  // to make OpenCV start 100000 threads and crash at exit).
  detect->add_option("--input-size", args->options.input_size, "Network input size (multiple of 32)")
      ->capture_default_str()
      ->check(CLI::Range(32, kMaxInputSize));
  detect->add_option("--confidence", args->options.confidence, "Confidence threshold")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  detect->add_option("--nms", args->options.nms, "NMS IoU threshold")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  detect->add_option("--person-class", args->options.person_class, "Person class index")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxPersonClass));
  detect->add_option("--threads", args->options.opencv_threads, "cv::setNumThreads for OpenCV (0 = leave)")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  detect->add_flag("--raw", args->raw, "Write every box above the threshold before NMS");
  detect->add_option("--max-frames", args->max_frames, "Stop after this many frames (0 = all)")
      ->check(CLI::Range(std::size_t{0}, kMaxFrames));
  detect->callback([args, &global] { run_detect(*args, global); });

  auto eval_args = std::make_shared<DetectEvalArgs>();
  CLI::App* eval = app.add_subcommand("detect-eval", "Precision, recall, MODA, MODP of MOT detections");
  eval->add_option("--gt", eval_args->ground_truth, "Ground truth (MOT15 10 columns or MOT16/17 9 columns)")
      ->required();
  eval->add_option("--det", eval_args->detections, "Detections (MOT format)")->required();
  eval->add_option("--iou", eval_args->options.iou_threshold, "IoU threshold of a match")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  eval->add_option("--min-visibility", eval_args->options.min_visibility,
                   "MOT16/17: pedestrians less visible than this are ignored")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  eval->callback([eval_args, &global] { run_detect_eval(*eval_args, global); });
}

}  // namespace crowdslam::app
