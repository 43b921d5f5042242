#pragma once
// Sequential-only sources through cv::VideoCapture (in the module of opencv_extras.h, loaded when a video
// or camera is opened): a video file or a live camera (index).
// Video frames get timestamps index / fps (DatasetOptions::fps, else the file's rate, else 30); camera
// frames get the seconds elapsed since the camera was opened (steady clock). No ground truth.
#include <chrono>
#include <memory>
#include <string>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/opencv_extras.h"

namespace crowdslam::io {

class VideoSource : public FrameSource {
 public:
  // Throws InputError naming the file when it cannot be opened or has no frames.
  static std::unique_ptr<VideoSource> open_file(const std::string& path, const DatasetOptions& options = {});
  // Throws InputError naming "camera N" when it cannot be opened.
  static std::unique_ptr<VideoSource> open_camera(int index, const DatasetOptions& options = {});

  [[nodiscard]] std::string path() const override { return path_; }
  [[nodiscard]] std::string layout() const override { return is_camera_ ? "camera" : "video"; }
  [[nodiscard]] SensorKind sensor() const override { return SensorKind::kMonocular; }
  std::optional<Frame> next() override;
  [[nodiscard]] SourceSummary summary() const override;
  [[nodiscard]] double fps() const { return fps_; }

 private:
  VideoSource(std::string path, bool is_camera) : path_(std::move(path)), is_camera_(is_camera) {}

  std::string path_;
  bool is_camera_ = false;
  std::unique_ptr<VideoCaptureHandle> capture_;
  double fps_ = 30.0;
  std::size_t frame_count_ = 0;  // from the container; 0 = unknown
  std::size_t next_index_ = 0;
  std::chrono::steady_clock::time_point opened_at_;
};

}  // namespace crowdslam::io
