#include "crowdslam/run/input_checks.h"

#include <spdlog/spdlog.h>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::run {

namespace {

std::string frame_name(const io::Frame& frame) {
  return frame.info.colour_path.empty() ? "frame " + std::to_string(frame.info.index) : clip_text(frame.info.colour_path);
}

std::string size_text(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

}  // namespace

void check_requested_sensor(const io::FrameSource& source, const std::optional<io::SensorKind>& requested) {
  if (!requested) return;
  const io::SensorKind available = source.sensor();
  const std::string dataset = clip_text(source.path());
  if (*requested == io::SensorKind::kRgbd && available != io::SensorKind::kRgbd) {
    throw InputError(dataset + ": --sensor rgbd needs a dataset with depth images (TUM/Bonn depth.txt); this one is " +
                     io::to_string(available));
  }
  if (*requested == io::SensorKind::kStereo && available != io::SensorKind::kStereo) {
    throw InputError(dataset + ": --sensor stereo needs a stereo dataset (EuRoC with cam1, KITTI with image_1); "
                     "this one is " + io::to_string(available));
  }
}

io::SensorKind choose_sensor(const io::FrameSource& source, const io::Settings& settings,
                             const std::optional<io::SensorKind>& requested) {
  check_requested_sensor(source, requested);
  if (requested) return *requested;
  const io::SensorKind available = source.sensor();
  const std::string dataset = clip_text(source.path());
  const std::string layout = source.layout();
  if (available != io::SensorKind::kMonocular) return available;
  const std::string settings_file = clip_text(settings.path);
  const bool stereo_layout = layout == "euroc" || layout == "kitti";
  const auto stereo_error = [&] {
    const std::string missing = layout == "euroc"   ? "no right camera (mav0/cam1)"
                                : layout == "kitti" ? "no right images (image_1/)"
                                                    : "no right images (" + layout + " layout)";
    return InputError(dataset + ": " + missing + ", but the settings " + settings_file +
                      " are for a stereo camera (Camera.bf); add the right images, or pass --sensor mono to run on "
                      "the left images only");
  };
  // EuRoC/KITTI are stereo layouts (ORB-SLAM2's stereo files may carry DepthMapFactor too).
  if (stereo_layout && settings.has_baseline) throw stereo_error();
  if (settings.has_depth_map_factor) {
    const std::string missing = layout == "tum" ? "no depth.txt" : "no depth images (" + layout + " layout)";
    throw InputError(dataset + ": " + missing + ", but the settings " + settings_file +
                     " are for an RGB-D camera (DepthMapFactor); add the depth images, or pass --sensor mono to "
                     "run on the colour images only");
  }
  if (settings.has_baseline) throw stereo_error();
  return available;
}

namespace {
void check_against_settings(const io::Frame& frame, const io::Settings& settings) {
  io::check_image_size(settings, frame.images.colour.size(), frame_name(frame));
}
}  // namespace

void check_first_frame(io::FrameSource& source, const io::Settings& settings, bool skip_bad_frames) {
  auto* dataset = dynamic_cast<io::Dataset*>(&source);
  if (dataset == nullptr || dataset->size() == 0) return;
  io::Frame frame{dataset->frame_info(0), {}};
  try {
    frame.images = dataset->load(0);
  } catch (const InputError&) {
    // With --skip-bad-frames an unreadable first frame is skipped like any other; the first frame read
    // is checked against the settings by InputMonitor.
    if (skip_bad_frames) return;
    throw;
  }
  check_against_settings(frame, settings);
}

void InputMonitor::check_frame(const io::Frame& frame) {
  check_timestamp(frame);
  const cv::Size size = frame.images.colour.size();
  if (!first_size_) {
    check_against_settings(frame, settings_);
    first_size_ = size;
    first_path_ = frame_name(frame);
  } else if (size != *first_size_) {
    throw InputError(frame_name(frame) + ": image is " + size_text(size.width, size.height) + ", the first frame (" +
                     first_path_ + ") was " + size_text(first_size_->width, first_size_->height) +
                     "; every frame of a sequence must have the same size");
  }
  if (sensor_ == io::SensorKind::kRgbd && !frame.images.depth.empty() && cv::countNonZero(frame.images.depth) == 0) {
    if (empty_depth_++ == 0) {
      first_empty_depth_ = frame.info.depth_path.empty() ? frame_name(frame) : clip_text(frame.info.depth_path);
      spdlog::warn("{}: depth image without any valid depth (all zero); such frames cannot be tracked in RGB-D",
                   first_empty_depth_);
    }
  }
}

void InputMonitor::check_timestamp(const io::Frame& frame) {
  const double stamp = frame.info.timestamp_s;
  if (previous_stamp_s_ && stamp <= *previous_stamp_s_) {
    if (backwards_++ == 0) {
      first_backwards_ = frame_name(frame);
      spdlog::warn("{}: timestamp {:.6f} is not after the previous frame's ({:.6f}); frames are taken in the "
                   "order listed (is the list reversed or unsorted?)",
                   first_backwards_, stamp, *previous_stamp_s_);
    }
  }
  previous_stamp_s_ = stamp;
}

void InputMonitor::after_tracking(const io::Frame& frame, int keypoints) {
  if (keypoints >= kFeaturelessKeypoints) return;
  if (featureless_++ == 0) {
    first_featureless_ = frame_name(frame);
    spdlog::warn("{}: only {} ORB keypoints (black, overexposed or featureless image?)", first_featureless_, keypoints);
  }
}

void InputMonitor::warn_totals() const {
  if (featureless_ > 1) {
    spdlog::warn("{} frames had fewer than {} ORB keypoints (first: {})", featureless_, kFeaturelessKeypoints,
                 first_featureless_);
  }
  if (backwards_ > 1) {
    spdlog::warn("{} frames had a timestamp not after the previous frame's (first: {})", backwards_, first_backwards_);
  }
  if (empty_depth_ > 1) {
    spdlog::warn("{} frames had no valid depth at all (first: {})", empty_depth_, first_empty_depth_);
  }
}

nlohmann::json InputMonitor::to_json() const {
  return {{"featureless_frames", featureless_},
          {"first_featureless_frame", first_featureless_.empty() ? nlohmann::json(nullptr) : nlohmann::json(first_featureless_)},
          {"empty_depth_frames", empty_depth_},
          {"timestamps_not_increasing", backwards_},
          {"first_empty_depth_frame", first_empty_depth_.empty() ? nlohmann::json(nullptr) : nlohmann::json(first_empty_depth_)}};
}

}  // namespace crowdslam::run
