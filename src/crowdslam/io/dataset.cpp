#include "crowdslam/io/dataset.h"

#include <cmath>
#include <filesystem>

#include "crowdslam/io/image_check.h"
#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {

std::string to_string(SensorKind sensor) {
  switch (sensor) {
    case SensorKind::kMonocular:
      return "monocular";
    case SensorKind::kStereo:
      return "stereo";
    case SensorKind::kRgbd:
      return "rgbd";
  }
  return "unknown";
}

SensorKind parse_sensor_kind(const std::string& name, const std::string& what) {
  if (name == "monocular" || name == "mono") return SensorKind::kMonocular;
  if (name == "stereo") return SensorKind::kStereo;
  if (name == "rgbd" || name == "rgb-d") return SensorKind::kRgbd;
  throw InputError(what + ": unknown sensor '" + name + "' (expected monocular, stereo or rgbd)");
}

void DatasetOptions::check() const {
  if (!std::isfinite(fps) || fps < 0.0)
    throw InputError("dataset option fps must be >= 0 (0 = default), got " + std::to_string(fps));
  if (!std::isfinite(max_time_difference_s) || max_time_difference_s <= 0.0)
    throw InputError("dataset option max_time_difference_s must be > 0, got " +
                     std::to_string(max_time_difference_s));
}

const Trajectory& FrameSource::ground_truth() const {
  static const Trajectory kEmpty;
  return kEmpty;
}

Dataset::Dataset(DatasetContents contents) : contents_(std::move(contents)) {}

std::optional<cv::Size> Dataset::reference_size(std::size_t index, const cv::Mat& colour) const {
  std::lock_guard<std::mutex> lock(reference_mutex_);
  if (!reference_known_) {
    if (index == 0) {
      reference_size_ = colour.size();
    } else {
      try {
        reference_size_ = read_colour_image(contents_.frames.front().colour_path).size();
      } catch (const InputError&) {  // reported when frame 0 itself is loaded
        reference_size_.reset();
      }
    }
    reference_known_ = true;
  }
  return reference_size_;
}

FrameImages Dataset::load(std::size_t index) const {
  const FrameInfo& info = frame_info(index);
  FrameImages images;
  images.colour = read_colour_image(info.colour_path);
  if (const auto expected = contents_.same_size_frames ? reference_size(index, images.colour) : std::nullopt;
      expected && images.colour.size() != *expected) {
    const auto text = [](const cv::Size& s) {
      return std::to_string(s.width) + "x" + std::to_string(s.height);
    };
    throw input_error(clip_text(info.colour_path),
                      "colour image is " + text(images.colour.size()) + ", but the first frame's (" +
                          clip_text(contents_.frames.front().colour_path) + ") is " + text(*expected) +
                          "; every frame of a sequence must have the same size");
  }
  if (!info.depth_path.empty()) {
    images.depth = read_depth_image(info.depth_path);
    check_same_size(images.depth, images.colour.size(), info.depth_path, "depth image");
  }
  if (!info.right_path.empty()) {
    images.right = read_colour_image(info.right_path);
    check_same_size(images.right, images.colour.size(), info.right_path, "right image");
  }
  return images;
}

std::optional<Frame> Dataset::next() {
  if (cursor_ >= size()) return std::nullopt;
  const std::size_t index = cursor_++;
  return Frame{frame_info(index), load(index)};
}

SourceSummary Dataset::summary() const {
  SourceSummary s;
  s.path = contents_.directory;
  s.layout = contents_.layout;
  s.sensor = contents_.sensor;
  s.frames = size();
  s.colour_entries = contents_.colour_entries;
  s.depth_entries = contents_.depth_entries;
  s.right_entries = contents_.right_entries;
  s.ground_truth_poses = contents_.ground_truth.size();
  s.ground_truth_path = contents_.ground_truth_path;
  if (!contents_.frames.empty()) {
    s.first_timestamp_s = contents_.frames.front().timestamp_s;
    s.last_timestamp_s = contents_.frames.back().timestamp_s;
  }
  s.fps = contents_.fps;
  s.settings_path = default_settings_path();
  return s;
}

std::string Dataset::default_settings_path() const {
  const auto candidate = std::filesystem::path(contents_.directory) / "settings.yaml";
  std::error_code ec;
  return std::filesystem::is_regular_file(candidate, ec) ? candidate.string() : std::string();
}

}  // namespace crowdslam::io
