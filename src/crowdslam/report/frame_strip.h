#pragma once
// The strip of saved frames (OUT/frames/NNNNNN.jpg, --save-frames): a few of them, evenly spread over
// the run, downscaled and re-encoded as JPEG data URLs so the report stays one file of reasonable size.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace crowdslam::report {

struct FrameStripOptions {
  size_t max_frames = 24;  // per run; evenly spread when the run saved more
  int width_px = 320;      // downscaled to this width (never upscaled)
  int jpeg_quality = 70;
  void check() const;  // throws InputError naming the bad value
};

struct EmbeddedFrame {
  long long frame_index = -1;  // from the file name (NNNNNN.jpg), -1 when it is not a number
  std::string data_url;        // "data:image/jpeg;base64,..."
};

// Indices of `count` items spread evenly over `available` (first and last included), all when
// available <= count.
std::vector<size_t> spread_indices(size_t available, size_t count);

// Unreadable images are skipped with a warning (the strip is an illustration, not data).
std::vector<EmbeddedFrame> embed_frames(const std::vector<std::filesystem::path>& files,
                                        const FrameStripOptions& options);

std::string base64_encode(const unsigned char* data, size_t size);

}  // namespace crowdslam::report
