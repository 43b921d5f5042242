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
#include "crowdslam/people/detection_metrics.h"
#include "crowdslam/people/detector_setup.h"
#include "crowdslam/people/dnn_detector.h"
#include "crowdslam/people/model_paths.h"
#include "crowdslam/people/mot_format.h"
#include "crowdslam/people/mot_sequence.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/progress.h"

namespace crowdslam::app {
namespace {

// `crowdslam detect`'s defaults without --settings: chosen for detection quality on the MOT sequences
// (docs/DETECTION.md, workflows/matrices/detectors.yaml); the model's own default input is in model_zoo.cpp.
// The SLAM filter's thresholds are the Detector.* keys of config/*.yaml, chosen for SLAM accuracy.
// YOLOX-nano COCO rather than ByteTrack-nano (as good on these sequences) because ByteTrack was trained
// on MOT17: its figures on MOT16/17 sequences would not be a test.
constexpr const char* kDefaultModel = "yolox";
constexpr double kDefaultConfidence = 0.3;
constexpr double kDefaultNms = 0.45;
constexpr int kMaxPersonClass = 9999;
constexpr int kMaxThreads = 64;
constexpr std::size_t kMaxFrames = 1000000000;

struct DetectArgs {
  std::string settings;
  std::string dataset;
  std::string out;
  std::string model = kDefaultModel;
  std::string input;  // --input WxH or S
  int input_size = 0;  // --input-size S (square, as before)
  std::string backend = "auto";
  std::string preprocess = "auto";
  std::string resize = "auto";
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

// Settings first (Detector.* keys, people/detector_setup.h), then the command-line options that were
// given explicitly. Without settings, the input is the model's detect default (model_zoo.cpp) and the
// thresholds those of DetectorOptions as set up in add_detect_command.
people::ModelFiles configure(DetectArgs& args) {
  const CLI::App& app = *args.app;
  io::DetectorSettings d;
  if (!args.settings.empty()) d = io::load_settings(args.settings, io::SensorKind::kMonocular).detector;
  if (given(app, "--backend")) d.backend = args.backend;
  if (given(app, "--preprocess")) d.preprocess = args.preprocess;
  if (given(app, "--resize")) d.resize = args.resize;
  // With settings, their model unless --model is given; without, --model or its default.
  const bool model_from_args = given(app, "--model") || args.settings.empty();
  const people::DetectorSetup setup = people::detector_setup(d, model_from_args ? args.model : std::string());
  people::ModelFiles model = setup.model;
  people::DetectorOptions& o = args.options;
  if (!args.settings.empty()) {
    o.input_size = setup.options.input_size;
    o.input_width = setup.options.input_width;
    o.input_height = setup.options.input_height;
    if (!given(app, "--confidence")) o.confidence = setup.options.confidence;
    if (!given(app, "--nms")) o.nms = setup.options.nms;
    if (!given(app, "--raw")) args.raw = d.filter_before_nms.value_or(true);
  } else if (model.detect_input.width > 0) {
    o.input_width = model.detect_input.width;
    o.input_height = model.detect_input.height;
  }
  o.resize = setup.options.resize;
  if (given(app, "--input") && given(app, "--input-size"))
    throw InputError("--input and --input-size: give one of them (--input-size S is --input S)");
  if (given(app, "--input")) {
    const cv::Size size = people::parse_input_size(args.input, "--input");
    o.input_width = size.width;
    o.input_height = size.height;
  }
  if (given(app, "--input-size")) {
    o.input_size = args.input_size;
    o.input_width = o.input_height = 0;
  }
  model.person_class = given(app, "--person-class") ? o.person_class : setup.options.person_class;
  o.person_class = model.person_class;
  o.check();
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
  people::DnnDetector detector(model, args.options);
  std::vector<people::FrameBoxes> frames;
  std::vector<double> times_ms;
  std::size_t boxes = 0;
  const std::size_t expected = source->summary().frames.value_or(0);
  const std::size_t total =
      args.max_frames > 0 && (expected == 0 || args.max_frames < expected) ? args.max_frames : expected;
  ProgressLine progress(!global.quiet, total, "frame");
  while (auto frame = source->next()) {
    if (args.max_frames > 0 && frames.size() >= args.max_frames) break;
    people::Detections d = detector.detect(frame->images.colour, frame->info.index);
    times_ms.push_back(d.time_ms);
    boxes += (args.raw ? d.raw : d.boxes).size();
    frames.push_back({frame->info.index, args.raw ? std::move(d.raw) : std::move(d.boxes)});
    progress.update(frames.size(), fmt::format("boxes {}  {:.1f} ms", frames.back().boxes.size(), d.time_ms));
  }
  progress.finish();
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
                {"input_width", args.options.input().width},
                {"input_height", args.options.input().height},
                {"backend", people::to_string(detector.backend())},
                {"preprocess", detector.preprocessing().name},
                {"resize", people::to_string(detector.preprocessing().resize)},
                {"confidence", args.options.confidence},
                {"nms", args.options.nms},
                {"before_nms", args.raw},
                {"frames", frames.size()},
                {"boxes", boxes},
                {"mean_time_ms", mean_ms},
                {"median_time_ms", median(times_ms)}});
    return;
  }
  std::printf("detector   %s (%s, %s, %s; %s)\n", detector.name().c_str(), people::to_string(detector.backend()),
              detector.preprocessing().name.c_str(), people::to_string(detector.preprocessing().resize),
              args.raw ? "boxes before NMS" : "after NMS");
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
  args->options.confidence = kDefaultConfidence;
  args->options.nms = kDefaultNms;
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
      ->add_option("--model,--detector", args->model,
                   people::zoo_model_names() + ", a Darknet .cfg (.weights beside it) or an .onnx file")
      ->capture_default_str();
  // Every numeric option is bounded here, so a bad value is a clear CLI error (e.g. --threads 100000 used
  // to make OpenCV start 100000 threads and crash at exit).
  detect->add_option("--input", args->input,
                     "Network input WIDTHxHEIGHT (e.g. 416x256) or SIZE (square); each a multiple of 32 "
                     "(default: the settings', else the model's: yolox 320x256, body/coco/bytetrack 416x320)");
  detect->add_option("--input-size", args->input_size, "Square network input (multiple of 32), as --input SIZE")
      ->check(CLI::Range(32, people::kMaxInputSide));
  detect->add_option("--backend", args->backend, "Decoder for a model given as a path: auto, darknet, yolo-onnx, yolox")
      ->check(CLI::IsMember({"auto", "darknet", "yolo-onnx", "yolox"}));
  detect->add_option("--preprocess", args->preprocess, "Preprocessing: auto (the model's), darknet, yolox, bytetrack")
      ->check(CLI::IsMember({"auto", "darknet", "yolox", "bytetrack"}));
  detect->add_option("--resize", args->resize, "Resize: auto (the preprocessing's), stretch, letterbox")
      ->check(CLI::IsMember({"auto", "stretch", "letterbox"}));
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
