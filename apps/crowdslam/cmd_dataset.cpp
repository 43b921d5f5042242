// `crowdslam dataset info SOURCE`: layout, sensor, counts, time span and image size of a dataset
// directory, video file or camera index (io::open_source).
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "crowdslam/io/dataset.h"

namespace crowdslam::app {
namespace {

struct DatasetInfoOptions {
  std::string source;
  double fps = 0.0;
  bool check = false;  // load and validate every frame
};

std::string frames_meaning(const io::SourceSummary& s) {
  if (s.sensor == io::SensorKind::kRgbd) return "associated colour-depth pairs";
  if (s.sensor == io::SensorKind::kStereo) return "stereo pairs";
  return "images";
}

std::string type_name(const cv::Mat& image) {
  if (image.empty()) return "";
  const int depth = image.depth();
  const std::string bits = depth == CV_8U ? "8U" : depth == CV_16U ? "16U" : depth == CV_32F ? "32F" : "?";
  return bits + "C" + std::to_string(image.channels());
}

nlohmann::json info_json(const io::SourceSummary& s, const io::Frame* first) {
  nlohmann::json j;
  j["path"] = s.path;
  j["layout"] = s.layout;
  j["sensor"] = io::to_string(s.sensor);
  j["frames"] = s.frames ? nlohmann::json(*s.frames) : nlohmann::json(nullptr);
  j["frames_are"] = frames_meaning(s);
  j["colour_frames"] = s.colour_entries;
  j["depth_frames"] = s.depth_entries;
  j["right_frames"] = s.right_entries;
  j["ground_truth_poses"] = s.ground_truth_poses;
  j["ground_truth_path"] = s.ground_truth_path;
  j["first_timestamp_s"] = s.first_timestamp_s;
  j["last_timestamp_s"] = s.last_timestamp_s;
  j["duration_s"] = s.last_timestamp_s - s.first_timestamp_s;
  j["fps"] = s.fps;
  j["settings"] = s.settings_path;
  j["width"] = first ? first->images.colour.cols : 0;
  j["height"] = first ? first->images.colour.rows : 0;
  j["colour_type"] = first ? type_name(first->images.colour) : "";
  j["depth_type"] = first ? type_name(first->images.depth) : "";
  return j;
}

void print_text(const nlohmann::json& j) {
  auto line = [](const char* label, const std::string& value) {
    std::printf("%-14s %s\n", label, value.c_str());
  };
  line("path:", j["path"].get<std::string>());
  line("layout:", j["layout"].get<std::string>());
  line("sensor:", j["sensor"].get<std::string>());
  line("frames:", (j["frames"].is_null() ? std::string("unknown (live)")
                                         : std::to_string(j["frames"].get<std::size_t>())) +
                      " (" + j["frames_are"].get<std::string>() + ")");
  line("colour frames:", std::to_string(j["colour_frames"].get<std::size_t>()));
  if (j["depth_frames"].get<std::size_t>() > 0)
    line("depth frames:", std::to_string(j["depth_frames"].get<std::size_t>()));
  if (j["right_frames"].get<std::size_t>() > 0)
    line("right frames:", std::to_string(j["right_frames"].get<std::size_t>()));
  const auto gt = j["ground_truth_poses"].get<std::size_t>();
  line("ground truth:",
       gt > 0 ? std::to_string(gt) + " poses (" + j["ground_truth_path"].get<std::string>() + ")" : "none");
  char span[160];
  std::snprintf(span, sizeof(span), "%.6f .. %.6f (%.3f s)", j["first_timestamp_s"].get<double>(),
                j["last_timestamp_s"].get<double>(), j["duration_s"].get<double>());
  line("time span:", span);
  std::string size = std::to_string(j["width"].get<int>()) + "x" + std::to_string(j["height"].get<int>()) +
                     " " + j["colour_type"].get<std::string>();
  if (!j["depth_type"].get<std::string>().empty()) size += ", depth " + j["depth_type"].get<std::string>();
  line("image size:", size);
  const auto settings = j["settings"].get<std::string>();
  line("settings:", settings.empty() ? "none in the dataset (pass one from config/)" : settings);
  if (j.contains("checked_frames"))
    line("checked:", std::to_string(j["checked_frames"].get<std::size_t>()) + " frames read and validated");
}

void run_info(const DatasetInfoOptions& options, const GlobalOptions& global) {
  io::DatasetOptions dataset_options;
  dataset_options.fps = options.fps;
  const std::unique_ptr<io::FrameSource> source = io::open_source(options.source, dataset_options);
  const io::SourceSummary summary = source->summary();
  const std::optional<io::Frame> first = source->next();
  nlohmann::json j = info_json(summary, first ? &*first : nullptr);
  if (options.check) {
    std::size_t checked = first ? 1 : 0;
    while (source->next()) ++checked;  // throws InputError naming the first bad file
    j["checked_frames"] = checked;
  }
  if (global.json) {
    print_json(j);
  } else {
    print_text(j);
  }
}

}  // namespace

void add_dataset_command(CLI::App& app, const GlobalOptions& global) {
  CLI::App* dataset =
      app.add_subcommand("dataset", "Inspect datasets (TUM/Bonn, EuRoC, KITTI, image folder, video)");
  dataset->require_subcommand(1);
  auto options = std::make_shared<DatasetInfoOptions>();
  CLI::App* info =
      dataset->add_subcommand("info", "Layout, sensor, frame counts, ground truth, time span, image size");
  info->add_option("source", options->source, "Dataset directory, video file or camera index")->required();
  info->add_option("--fps", options->fps, "Frame rate for image folders / videos (default: file's or 30)")
      ->check(CLI::Range(0.0, 10000.0));
  info->add_flag("--check", options->check,
                 "Read and validate every frame (end markers, decoding, depth type/size)");
  info->callback([options, &global] { run_info(*options, global); });
}

}  // namespace crowdslam::app
