// The module behind io/opencv_extras.h: OpenCV's imgcodecs and videoio, linked here and only here.
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "crowdslam/io/opencv_extras.h"

namespace crowdslam::io {
namespace {

class Capture final : public VideoCaptureHandle {
 public:
  bool open_file(const std::string& path) override {
    // FFmpeg handles nearly every file; OpenCV's own MJPEG reader and image-sequence patterns as
    // fallbacks. GStreamer is left out: it adds nothing for files here and its plugin scan leaks
    // (libusb) under LeakSanitizer.
    for (const int backend : {cv::CAP_FFMPEG, cv::CAP_OPENCV_MJPEG, cv::CAP_IMAGES})
      if (capture_.open(path, backend)) return true;
    return false;
  }
  bool open_camera(int index) override { return capture_.open(index); }
  [[nodiscard]] bool is_opened() const override { return capture_.isOpened(); }
  [[nodiscard]] double fps() const override { return capture_.get(cv::CAP_PROP_FPS); }
  [[nodiscard]] double frame_count() const override { return capture_.get(cv::CAP_PROP_FRAME_COUNT); }
  bool read(cv::Mat& image) override { return capture_.read(image); }

 private:
  cv::VideoCapture capture_;
};

class Extras final : public OpenCvExtras {
 public:
  [[nodiscard]] cv::Mat imdecode(const std::vector<unsigned char>& bytes, int flags) const override {
    return cv::imdecode(bytes, flags);
  }
  [[nodiscard]] cv::Mat imread(const std::string& path, int flags) const override {
    return cv::imread(path, flags);
  }
  bool imwrite(const std::string& path, const cv::Mat& image, const std::vector<int>& params) const override {
    return cv::imwrite(path, image, params);
  }
  bool imencode(const std::string& extension, const cv::Mat& image, std::vector<unsigned char>& out,
                const std::vector<int>& params) const override {
    return cv::imencode(extension, image, out, params);
  }
  [[nodiscard]] std::unique_ptr<VideoCaptureHandle> video_capture() const override {
    return std::make_unique<Capture>();
  }
};

}  // namespace
}  // namespace crowdslam::io

extern "C" __attribute__((visibility("default"))) const crowdslam::io::OpenCvExtras* crowdslam_opencv_extras() {
  static const crowdslam::io::Extras extras;
  return &extras;
}
