#pragma once
// A "detector" that reads boxes from a MOT-format file (frame,id,x,y,w,h,conf,...), so boxes from any
// external detector, or the synthetic generator's ground truth, can drive the system.
//
// - Frames are 1-based in the file; detect(image, frame_index) returns the boxes of MOT frame
//   frame_index + 1. Frames absent from the file (including every frame after the file's last one, when
//   the file is shorter than the sequence) have no boxes.
// - Rows with conf < DetectorOptions::confidence are dropped (files without a 7th column count as 1).
// - Boxes are clipped to the image given to detect(); boxes with zero or negative size or beyond
//   kMaxBoxCoordinate are skipped when the file is read (counted and warned once, mot_format.h), and
//   boxes with nothing left after clipping are dropped.
// - NaN / infinite / non-numeric fields make the constructor throw InputError "FILE:LINE: ..." (a broken
//   file is reported before any frame is processed; never a crash).
// - Boxes are used as given: `boxes` and `raw` are the same (no NMS; the external detector did that).
#include <map>
#include <string>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

class MotFileDetector : public PersonDetector {
 public:
  MotFileDetector(const std::string& path, const DetectorOptions& options);

  Detections detect(const cv::Mat& bgr, std::size_t frame_index) override;
  [[nodiscard]] std::string name() const override { return "mot-file:" + path_; }
  [[nodiscard]] bool reads_pixels() const override { return false; }

  [[nodiscard]] int last_frame() const;  // largest 1-based frame with a box, 0 if none
  [[nodiscard]] std::size_t box_count() const { return box_count_; }  // after the confidence threshold
  [[nodiscard]] std::size_t dropped_empty() const { return dropped_empty_; }

 private:
  std::string path_;
  std::map<int, std::vector<PersonBox>> boxes_by_frame_;  // 1-based frame -> boxes
  std::size_t box_count_ = 0;
  std::size_t dropped_empty_ = 0;
};

}  // namespace crowdslam::people
