#pragma once
// JPEG encoding with libjpeg(-turbo) directly (the viewer's image stream, saved frames, the report's
// frame strip), so that a run needs none of OpenCV's image codecs (opencv_extras.h).
#include <opencv2/core.hpp>
#include <vector>

namespace crowdslam::io {

// Baseline JPEG of an 8-bit grey (CV_8UC1) or BGR (CV_8UC3) image at `quality` (1-100; libjpeg's
// default settings otherwise: 4:2:0 chroma subsampling, as cv::imencode). Throws InputError for an
// empty image, another type, or a quality out of range; std::runtime_error when libjpeg fails.
std::vector<unsigned char> encode_jpeg(const cv::Mat& image, int quality);

}  // namespace crowdslam::io
