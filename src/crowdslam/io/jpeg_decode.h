#pragma once
// JPEG decoding with libjpeg(-turbo) directly (internal to io; used by image_check.cpp).
//
// cv::imread lets libjpeg print "Corrupt JPEG data: ..." on stderr and returns the damaged image; here
// every libjpeg error AND warning (premature end of data, extraneous bytes before a marker, a missing
// end-of-image marker, ...) is an InputError naming the file and libjpeg's message, and libjpeg prints
// nothing. Bytes after the end-of-image marker are ignored, as libjpeg and cv::imread do.
//
// The result is what cv::imread(path, cv::IMREAD_ANYCOLOR) gives for a valid file: 8-bit BGR for
// colour (3 components; CMYK/YCCK converted as OpenCV does), 8-bit grey for greyscale, EXIF
// orientation applied; same libjpeg, same (default) DCT and upsampling, so the pixels are identical.
#include <cstddef>
#include <opencv2/core.hpp>
#include <string>

namespace crowdslam::io {

// `data` must start with the JPEG SOI marker (FF D8). Throws InputError "PATH: ..." on any error or
// warning, or for an image of more than kMaxImagePixels pixels.
cv::Mat decode_jpeg(const unsigned char* data, std::size_t size, const std::string& path);

// Largest image we decode (width * height); bigger ones are refused before memory is allocated.
constexpr double kMaxImagePixels = 1 << 28;

}  // namespace crowdslam::io
