#pragma once
// Reading dataset images with validation: every failure is an InputError naming the file.
//
// cv::imread happily returns a partly grey image for a truncated or corrupt JPEG (libjpeg only prints
// a warning on stderr that names no file) and lets libpng print its complaints too. So:
//   - JPEG (starts FF D8) is decoded with libjpeg directly (jpeg_decode.h): every libjpeg error or
//     warning is an InputError naming the file and libjpeg's message. Bytes after the end-of-image
//     marker are accepted (some writers pad files). JPEG has no checksum: damage that libjpeg decodes
//     without complaint (a single flipped bit often is: Huffman codes resynchronise) cannot be found;
//     truncation and damaged runs of bytes practically always are.
//   - PNG: before decoding, the chunk structure is walked and every chunk's CRC checked; a file cut
//     short (before IEND) or with a flipped bit is an error naming the file, and libpng never sees it.
//     The common PNGs (8/16-bit grey, RGB, RGBA, not interlaced: depth maps, KITTI/TUM images) are then
//     decoded by png_decode.h (libdeflate, about 3 times faster, same pixels; image data that does not
//     inflate or inflates short is an error naming the file); the rest by cv::imdecode.
//   - Other formats are only checked by decoding (cv::imdecode, through opencv_extras.h).
// Files are read into memory once; decoding does not touch the disk again.
#include <opencv2/core.hpp>
#include <string>

namespace crowdslam::io {

// Colour or grey image as stored (8-bit BGR or 8-bit grey; 16-bit and alpha are reduced as OpenCV's
// IMREAD_ANYCOLOR does; EXIF orientation applied as cv::imread does). Same pixels as
// cv::imread(path, cv::IMREAD_ANYCOLOR) for a valid file. Throws InputError naming `path` when it is
// missing, not a regular file, empty, truncated, corrupt or undecodable.
cv::Mat read_colour_image(const std::string& path);

// As read_colour_image, with grey images made 3-channel: what cv::imread(path, cv::IMREAD_COLOR) gives.
cv::Mat read_bgr_image(const std::string& path);

// A mask: 255 where the stored image is non-zero in any channel, else 0 (8-bit single-channel). Reads 8-
// and 16-bit images as stored, so a 16-bit id image (synth's people_mask/) is not reduced to 8 bits
// first. Throws InputError naming `path` as read_colour_image does.
cv::Mat read_mask_image(const std::string& path);

// Raw 16-bit single-channel depth (values as stored, metres = value / DepthMapFactor). Throws InputError
// naming `path` for any other type (e.g. an 8-bit depth image) or when missing/truncated/undecodable.
cv::Mat read_depth_image(const std::string& path);

// Throws InputError naming `path` unless `image` has the size `expected` ("depth image" / "right image"
// names what is being compared in the message).
void check_same_size(const cv::Mat& image, const cv::Size& expected, const std::string& path,
                     const std::string& what);

}  // namespace crowdslam::io
