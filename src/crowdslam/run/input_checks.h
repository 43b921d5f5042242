#pragma once
// Checks of the run's inputs that need both the dataset and the settings (the readers check each alone):
//   - before the first frame: the dataset gives what the sensor the settings describe needs;
//   - per frame: image size against Camera.width/height and against the first frame; frames without
//     features (black, overexposed or featureless) and RGB-D frames without any depth are counted and
//     warned about once, with the first frame's file.
#include <cstddef>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"

namespace crowdslam::run {

// The sensor the run uses. Without `requested` (--sensor), the dataset's sensor, unless the settings
// file describes a camera the dataset cannot feed (RGB-D settings, DepthMapFactor, on a dataset without
// depth; stereo settings, Camera.bf without DepthMapFactor, on EuRoC/KITTI without the right camera):
// then an InputError naming what is missing and pointing at --sensor mono. An explicit --sensor rgbd or
// stereo on a dataset without depth / right images is an error too.
// An explicit --sensor the dataset cannot feed (rgbd without depth, stereo without right images).
void check_requested_sensor(const io::FrameSource& source, const std::optional<io::SensorKind>& requested);
// `settings` loaded for requested.value_or(source.sensor()).
io::SensorKind choose_sensor(const io::FrameSource& source, const io::Settings& settings,
                             const std::optional<io::SensorKind>& requested);

// Before any output exists: the first frame of a dataset on disk is read and its size compared with
// Camera.width/height (videos and cameras are checked at their first frame by InputMonitor).
void check_first_frame(io::FrameSource& source, const io::Settings& settings, bool skip_bad_frames = false);

class InputMonitor {
 public:
  InputMonitor(const io::Settings& settings, io::SensorKind sensor) : settings_(settings), sensor_(sensor) {}

  // Before tracking a frame: throws InputError for an image of the wrong size (naming the file, both
  // sizes and the settings file); counts RGB-D frames without depth and warns (once, then in the totals)
  // about a timestamp that is not after the previous frame's.
  void check_frame(const io::Frame& frame);
  // After tracking it: counts frames whose image gave (almost) no ORB keypoints.
  void after_tracking(const io::Frame& frame, int keypoints);
  // Warns the totals once at the end (when any); the counts for run.json.
  void warn_totals() const;
  [[nodiscard]] nlohmann::json to_json() const;

  static constexpr int kFeaturelessKeypoints = 20;

 private:
  const io::Settings& settings_;
  io::SensorKind sensor_;
  std::optional<cv::Size> first_size_;
  std::string first_path_;
  size_t featureless_ = 0;
  std::string first_featureless_;
  void check_timestamp(const io::Frame& frame);
  std::optional<double> previous_stamp_s_;
  size_t backwards_ = 0;
  std::string first_backwards_;
  size_t empty_depth_ = 0;
  std::string first_empty_depth_;
};

}  // namespace crowdslam::run
