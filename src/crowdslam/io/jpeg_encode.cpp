#include "crowdslam/io/jpeg_encode.h"

#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
// jpeglib.h needs FILE and size_t declared first.
// clang-format off
#include <jpeglib.h>
// clang-format on

#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace {

struct EncodeErrors {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void on_encode_error(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<EncodeErrors*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
  std::longjmp(err->jump, 1);
}

void print_no_encode_message(j_common_ptr) {}

// Everything between setjmp and longjmp is trivially destructible: libjpeg's memory destination
// (malloc'ed by libjpeg) is freed by the caller.
bool run_encode(jpeg_compress_struct& cinfo, EncodeErrors& err, const cv::Mat& image, int quality,
                unsigned char** buffer, unsigned long* size) {
  cinfo.err = jpeg_std_error(&err.pub);
  err.pub.error_exit = on_encode_error;
  err.pub.output_message = print_no_encode_message;
  if (setjmp(err.jump) != 0) {
    jpeg_destroy_compress(&cinfo);
    return false;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, buffer, size);
  cinfo.image_width = static_cast<JDIMENSION>(image.cols);
  cinfo.image_height = static_cast<JDIMENSION>(image.rows);
  const bool grey = image.channels() == 1;
  cinfo.input_components = grey ? 1 : 3;
  cinfo.in_color_space = grey ? JCS_GRAYSCALE : JCS_EXT_BGR;  // libjpeg-turbo's BGR input
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, quality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(image.ptr<unsigned char>(static_cast<int>(cinfo.next_scanline)));
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  return true;
}

}  // namespace

std::vector<unsigned char> encode_jpeg(const cv::Mat& image, int quality) {
  if (image.empty()) throw InputError("encode_jpeg: empty image");
  if (image.type() != CV_8UC1 && image.type() != CV_8UC3)
    throw InputError("encode_jpeg: image must be 8-bit grey or BGR, got type " + std::to_string(image.type()));
  if (quality < 1 || quality > 100)
    throw InputError("encode_jpeg: quality must be in [1, 100], got " + std::to_string(quality));
  jpeg_compress_struct cinfo{};
  EncodeErrors err{};
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  const bool ok = run_encode(cinfo, err, image, quality, &buffer, &size);
  std::vector<unsigned char> out;
  if (ok) out.assign(buffer, buffer + size);
  std::free(buffer);
  if (!ok) throw std::runtime_error(std::string("JPEG encoding failed: ") + err.message);
  return out;
}

}  // namespace crowdslam::io
