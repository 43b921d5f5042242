#pragma once
// OpenCV's image codecs (imgcodecs) and video input (videoio), loaded on first use.
//
// Those two OpenCV libraries bring in about 200 shared libraries (GDAL, GDCM, FFmpeg, GStreamer, ...):
// linked into a program, they cost it about 55 MB of resident memory and 0.2 s of CPU at start-up,
// before any frame. crowdslam decodes JPEG and PNG itself (jpeg_decode.h, png_decode.h) and encodes JPEG
// itself (jpeg_encode.h), so a run on JPEG or PNG images never needs them. What does (other image formats,
// the PNGs the decoder leaves to OpenCV, video files, cameras, the synthetic generator's PNG writer) goes
// through this interface, implemented by the module `crowdslam_opencv_extras` (extras/opencv_extras.cpp),
// which is loaded with dlopen the first time it is asked for.
//
// The module is looked for at $CROWDSLAM_OPENCV_EXTRAS, else beside the executable or shared library that
// holds this code (the installed Python package), else at the path the build wrote it to.
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace crowdslam::io {

// A cv::VideoCapture behind the module boundary. OpenCV's exceptions (cv::Exception) pass through.
class VideoCaptureHandle {
 public:
  virtual ~VideoCaptureHandle() = default;
  // A file through FFmpeg, else OpenCV's MJPEG reader, else an image-sequence pattern ("img_%04d.png").
  virtual bool open_file(const std::string& path) = 0;
  virtual bool open_camera(int index) = 0;
  [[nodiscard]] virtual bool is_opened() const = 0;
  [[nodiscard]] virtual double fps() const = 0;          // CAP_PROP_FPS; 0 or NaN when unknown
  [[nodiscard]] virtual double frame_count() const = 0;  // CAP_PROP_FRAME_COUNT; <= 0 when unknown
  virtual bool read(cv::Mat& image) = 0;
};

// The functions of cv::imdecode, cv::imread, cv::imwrite and cv::imencode (same flags and parameters).
class OpenCvExtras {
 public:
  virtual ~OpenCvExtras() = default;
  [[nodiscard]] virtual cv::Mat imdecode(const std::vector<unsigned char>& bytes, int flags) const = 0;
  [[nodiscard]] virtual cv::Mat imread(const std::string& path, int flags) const = 0;
  virtual bool imwrite(const std::string& path, const cv::Mat& image, const std::vector<int>& params) const = 0;
  virtual bool imencode(const std::string& extension, const cv::Mat& image, std::vector<unsigned char>& out,
                        const std::vector<int>& params) const = 0;
  [[nodiscard]] virtual std::unique_ptr<VideoCaptureHandle> video_capture() const = 0;
};

// The module, loaded on the first call (thread-safe; it stays loaded). Throws std::runtime_error naming
// the module's path and the loader's message when it cannot be loaded.
const OpenCvExtras& opencv_extras();

}  // namespace crowdslam::io
