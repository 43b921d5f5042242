#include "crowdslam/people/mot_file_detector.h"

#include <chrono>

#include "crowdslam/people/mot_format.h"

namespace crowdslam::people {

MotFileDetector::MotFileDetector(const std::string& path, const DetectorOptions& options) : path_(path) {
  options.check();
  const MotFile file = read_mot_file(path);
  dropped_empty_ = file.dropped_empty;  // read_mot_file warned about the skipped rows
  for (const MotRow& row : file.rows) {
    if (row.score < options.confidence) continue;
    boxes_by_frame_[row.frame].push_back({row.box, static_cast<float>(row.score)});
    ++box_count_;
  }
}

int MotFileDetector::last_frame() const {
  return boxes_by_frame_.empty() ? 0 : boxes_by_frame_.rbegin()->first;
}

Detections MotFileDetector::detect(const cv::Mat& bgr, std::size_t frame_index) {
  const auto start = std::chrono::steady_clock::now();
  Detections result;
  const auto it = boxes_by_frame_.find(static_cast<int>(frame_index + 1));
  if (it != boxes_by_frame_.end()) {
    for (const PersonBox& b : it->second) {
      const cv::Rect2f clipped = clip_box(b.box, bgr.cols, bgr.rows);
      if (clipped.width > 0 && clipped.height > 0) result.boxes.push_back({clipped, b.confidence});
    }
  }
  result.raw = result.boxes;
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace crowdslam::people
