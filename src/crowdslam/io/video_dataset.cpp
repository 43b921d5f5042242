#include "crowdslam/io/video_dataset.h"

#include <cmath>
#include <filesystem>

#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {

std::unique_ptr<VideoSource> VideoSource::open_file(const std::string& path, const DatasetOptions& options) {
  options.check();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw input_error(clip_text(path), "video file does not exist");
  std::unique_ptr<VideoSource> source(new VideoSource(path, false));
  source->capture_ = opencv_extras().video_capture();
  try {
    source->capture_->open_file(path);  // FFmpeg, OpenCV's MJPEG reader, image-sequence patterns
  } catch (const cv::Exception& e) {
    throw input_error(path, std::string("cannot open video: ") + e.what());
  }
  if (!source->capture_->is_opened())
    throw input_error(path, "cannot open as a video (unknown format or corrupt file)");
  const double file_fps = source->capture_->fps();
  source->fps_ = options.fps > 0 ? options.fps : (std::isfinite(file_fps) && file_fps > 0 ? file_fps : 30.0);
  const double count = source->capture_->frame_count();
  source->frame_count_ = std::isfinite(count) && count > 0 ? static_cast<std::size_t>(count) : 0;
  source->opened_at_ = std::chrono::steady_clock::now();
  return source;
}

std::unique_ptr<VideoSource> VideoSource::open_camera(int index, const DatasetOptions& options) {
  options.check();
  const std::string name = "camera " + std::to_string(index);
  std::unique_ptr<VideoSource> source(new VideoSource(name, true));
  source->capture_ = opencv_extras().video_capture();
  try {
    source->capture_->open_camera(index);
  } catch (const cv::Exception& e) {
    throw input_error(name, std::string("cannot open: ") + e.what());
  }
  if (!source->capture_->is_opened()) throw input_error(name, "cannot open camera");
  const double camera_fps = source->capture_->fps();
  source->fps_ =
      options.fps > 0 ? options.fps : (std::isfinite(camera_fps) && camera_fps > 0 ? camera_fps : 30.0);
  source->opened_at_ = std::chrono::steady_clock::now();
  return source;
}

std::optional<Frame> VideoSource::next() {
  Frame frame;
  bool ok = false;
  try {
    ok = capture_->read(frame.images.colour);
  } catch (const cv::Exception& e) {
    throw input_error(path_, "frame " + std::to_string(next_index_) + ": cannot decode: " + e.what());
  }
  if (!ok || frame.images.colour.empty()) return std::nullopt;
  frame.info.index = next_index_++;
  if (is_camera_) {
    frame.info.timestamp_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - opened_at_).count();
  } else {
    frame.info.timestamp_s = static_cast<double>(frame.info.index) / fps_;
  }
  return frame;
}

SourceSummary VideoSource::summary() const {
  SourceSummary s;
  s.path = path_;
  s.layout = layout();
  s.sensor = sensor();
  s.fps = fps_;
  if (!is_camera_ && frame_count_ > 0) {
    s.frames = frame_count_;
    s.colour_entries = frame_count_;
    s.last_timestamp_s = static_cast<double>(frame_count_ - 1) / fps_;
  }
  return s;
}

}  // namespace crowdslam::io
