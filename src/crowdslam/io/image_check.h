#pragma once
// Reading dataset images with validation: every failure is an InputError naming the file.
//
// cv::imread happily returns a partly grey image for a truncated JPEG, so before decoding we check the
// file's end marker: a JPEG (starts FF D8) must end with FF D9 (trailing zero padding allowed), a PNG
// must end with its IEND chunk. Other formats are only checked by decoding.
#include <opencv2/core.hpp>
#include <string>

namespace crowdslam::io {

// Throws InputError naming `path` if the file is missing, empty, or a truncated JPEG/PNG.
void check_image_file_complete(const std::string& path);

// Colour or grey image as stored (8-bit BGR or 8-bit grey; 16-bit and alpha are reduced by OpenCV's
// IMREAD_ANYCOLOR). Throws InputError naming `path` when missing, truncated or undecodable.
cv::Mat read_colour_image(const std::string& path);

// Raw 16-bit single-channel depth (values as stored, metres = value / DepthMapFactor). Throws InputError
// naming `path` for any other type (e.g. an 8-bit depth image) or when missing/truncated/undecodable.
cv::Mat read_depth_image(const std::string& path);

// Throws InputError naming `path` unless `image` has the size `expected` ("depth" / "right image" names
// what is being compared in the message).
void check_same_size(const cv::Mat& image, const cv::Size& expected, const std::string& path,
                     const std::string& what);

}  // namespace crowdslam::io
