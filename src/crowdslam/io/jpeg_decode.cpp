#include "crowdslam/io/jpeg_decode.h"

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstring>
// jpeglib.h needs FILE and size_t declared first, jerror.h needs jpeglib.h.
// clang-format off
#include <jpeglib.h>
#include <jerror.h>
// clang-format on

#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace {

// libjpeg reports through these callbacks; both errors and warnings end the decode (longjmp back to
// run_decode), and nothing is printed.
struct ErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
  bool warning;
  int code;  // libjpeg's message code
};

void on_error(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<ErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
  err->warning = false;
  err->code = cinfo->err->msg_code;
  std::longjmp(err->jump, 1);
}

void on_message(j_common_ptr cinfo, int level) {
  if (level >= 0) return;  // trace messages
  auto* err = reinterpret_cast<ErrorManager*>(cinfo->err);
  ++cinfo->err->num_warnings;
  (*cinfo->err->format_message)(cinfo, err->message);
  err->warning = true;
  err->code = cinfo->err->msg_code;
  std::longjmp(err->jump, 1);
}

void print_nothing(j_common_ptr) {}

// Everything run_decode touches between setjmp and longjmp is trivially destructible (the output
// cv::Mats belong to the caller), so the jump skips no destructor.
struct Job {
  jpeg_decompress_struct cinfo;
  ErrorManager err;
  bool too_large;
  unsigned width, height;  // of a too large image
  int orientation;         // EXIF orientation 1..8
};

unsigned read16(const unsigned char* p, bool little) {
  return little ? (p[0] | (p[1] << 8)) : ((p[0] << 8) | p[1]);
}
unsigned long read32(const unsigned char* p, bool little) {
  return little ? (p[0] | (p[1] << 8) | (p[2] << 16) | (static_cast<unsigned long>(p[3]) << 24))
                : ((static_cast<unsigned long>(p[0]) << 24) | (p[1] << 16) | (p[2] << 8) | p[3]);
}

// Orientation tag (0x0112) of IFD0 in an APP1 "Exif" marker; 1 (as stored) when absent or malformed.
int exif_orientation(jpeg_saved_marker_ptr marker) {
  for (; marker != nullptr; marker = marker->next) {
    if (marker->marker != JPEG_APP0 + 1 || marker->data_length < 14) continue;
    const unsigned char* d = marker->data;
    if (std::memcmp(d, "Exif\0\0", 6) != 0) continue;
    const unsigned char* tiff = d + 6;
    const std::size_t size = marker->data_length - 6;
    const bool little = tiff[0] == 'I' && tiff[1] == 'I';
    if (!little && !(tiff[0] == 'M' && tiff[1] == 'M')) return 1;
    const unsigned long ifd = read32(tiff + 4, little);
    if (ifd + 2 > size) return 1;
    const unsigned count = read16(tiff + ifd, little);
    for (unsigned i = 0; i < count; ++i) {
      const std::size_t entry = ifd + 2 + 12 * static_cast<std::size_t>(i);
      if (entry + 12 > size) return 1;
      if (read16(tiff + entry, little) != 0x0112) continue;
      const unsigned value = read16(tiff + entry + 8, little);
      return value >= 1 && value <= 8 ? static_cast<int>(value) : 1;
    }
    return 1;
  }
  return 1;
}

// false when libjpeg reported an error or a warning (job.err.message) or the image is too large.
bool run_decode(Job& job, const unsigned char* data, std::size_t size, cv::Mat& out, cv::Mat& cmyk) {
  jpeg_decompress_struct& cinfo = job.cinfo;
  if (setjmp(job.err.jump) != 0) return false;
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
  jpeg_save_markers(&cinfo, JPEG_APP0 + 1, 0xFFFF);
  jpeg_read_header(&cinfo, TRUE);
  if (static_cast<double>(cinfo.image_width) * cinfo.image_height > kMaxImagePixels) {
    job.too_large = true;
    job.width = cinfo.image_width;
    job.height = cinfo.image_height;
    return false;
  }
  cv::Mat* target = &out;
  if (cinfo.num_components == 1) {
    cinfo.out_color_space = JCS_GRAYSCALE;
  } else if (cinfo.num_components == 4) {
    cinfo.out_color_space = JCS_CMYK;  // CMYK or YCCK (Adobe): converted to BGR below, as OpenCV does
    target = &cmyk;
  } else {
    cinfo.out_color_space = JCS_EXT_BGR;
  }
  jpeg_start_decompress(&cinfo);
  const int height = static_cast<int>(cinfo.output_height);
  const int width = static_cast<int>(cinfo.output_width);
  target->create(height, width, CV_8UC(cinfo.output_components));
  constexpr int kRows = 16;
  JSAMPROW rows[kRows];
  while (cinfo.output_scanline < cinfo.output_height) {
    const int first = static_cast<int>(cinfo.output_scanline);
    const int count = std::min(kRows, height - first);
    for (int k = 0; k < count; ++k) rows[k] = target->ptr<JSAMPLE>(first + k);
    jpeg_read_scanlines(&cinfo, rows, static_cast<JDIMENSION>(count));
  }
  job.orientation = exif_orientation(cinfo.marker_list);
  jpeg_finish_decompress(&cinfo);
  return true;
}

// OpenCV's CMYK -> BGR (Adobe CMYK JPEGs store inverted values).
void cmyk_to_bgr(const cv::Mat& cmyk, cv::Mat& bgr) {
  bgr.create(cmyk.size(), CV_8UC3);
  for (int r = 0; r < cmyk.rows; ++r) {
    const uchar* in = cmyk.ptr<uchar>(r);
    uchar* out = bgr.ptr<uchar>(r);
    for (int c = 0; c < cmyk.cols; ++c, in += 4, out += 3) {
      const int k = in[3];
      out[2] = static_cast<uchar>(k - ((255 - in[0]) * k >> 8));
      out[1] = static_cast<uchar>(k - ((255 - in[1]) * k >> 8));
      out[0] = static_cast<uchar>(k - ((255 - in[2]) * k >> 8));
    }
  }
}

// As cv::imread's EXIF handling.
void apply_orientation(cv::Mat& image, int orientation) {
  switch (orientation) {
    case 2:
      cv::flip(image, image, 1);
      break;
    case 3:
      cv::flip(image, image, -1);
      break;
    case 4:
      cv::flip(image, image, 0);
      break;
    case 5:
      cv::transpose(image, image);
      break;
    case 6:
      cv::transpose(image, image);
      cv::flip(image, image, 1);
      break;
    case 7:
      cv::transpose(image, image);
      cv::flip(image, image, -1);
      break;
    case 8:
      cv::transpose(image, image);
      cv::flip(image, image, 0);
      break;
    default:
      break;
  }
}

}  // namespace

cv::Mat decode_jpeg(const unsigned char* data, std::size_t size, const std::string& path) {
  Job job;
  std::memset(&job, 0, sizeof(job));
  job.orientation = 1;
  job.cinfo.err = jpeg_std_error(&job.err.pub);
  job.err.pub.error_exit = on_error;
  job.err.pub.emit_message = on_message;
  job.err.pub.output_message = print_nothing;
  cv::Mat out;
  cv::Mat cmyk;
  bool ok = false;
  try {
    ok = run_decode(job, data, size, out, cmyk);
  } catch (...) {  // allocation failure in cv::Mat::create
    jpeg_destroy_decompress(&job.cinfo);
    throw;
  }
  jpeg_destroy_decompress(&job.cinfo);
  if (job.too_large)
    throw input_error(clip_text(path), "JPEG image of " + std::to_string(job.width) + "x" +
                                         std::to_string(job.height) + " pixels is too large");
  if (!ok) {
    const bool truncated = job.err.code == JWRN_JPEG_EOF || job.err.code == JERR_INPUT_EOF;
    const std::string what = truncated         ? "truncated JPEG image: "
                             : job.err.warning ? "corrupt JPEG image: "
                                               : "cannot decode JPEG image: ";
    throw input_error(clip_text(path), what + job.err.message);
  }
  if (!cmyk.empty()) cmyk_to_bgr(cmyk, out);
  apply_orientation(out, job.orientation);
  return out;
}

}  // namespace crowdslam::io
