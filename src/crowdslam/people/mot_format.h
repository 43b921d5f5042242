#pragma once
// MOTChallenge text files: detections and ground truth, one box per line,
//   frame, id, left, top, width, height, conf/flag [, class, visibility] or [, x, y, z]
// comma separated (spaces accepted too), frames 1-based. Blank lines and lines starting with '#' are
// skipped.
//
// Reading is strict: a line with fewer than 6 fields, a field that is not a number, or a NaN / infinite
// value in any of the first 7 fields throws InputError "FILE:LINE: ..." (a broken file is reported, never
// silently half-used). A frame number that is not an integer >= 1 is an error too. Boxes with zero or
// negative width or height, or a coordinate or size beyond +-kMaxBoxCoordinate pixels, are NOT errors:
// the reader skips them, counts them (`dropped_empty`, `dropped_out_of_range`) and warns once
// (spdlog::warn) naming FILE:LINE of the first one and the counts.
#include <cstddef>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

struct MotRow {
  int frame = 0;  // 1-based
  int id = -1;
  cv::Rect2f box;
  double score = 1.0;        // column 7: confidence (detections) or flag (ground truth); 1 when absent
  int object_class = -1;     // column 8 of 9-column MOT16/17 ground truth, else -1
  double visibility = -1.0;  // column 9 of 9-column MOT16/17 ground truth, else -1
  int line = 0;              // 1-based line in the file
};

// Larger than any image side: a box beyond it is a broken row, not a person.
constexpr double kMaxBoxCoordinate = 1e6;

struct MotFile {
  std::string path;
  std::size_t columns = 0;               // field count of the rows (all rows must agree)
  std::vector<MotRow> rows;              // rows with a positive-size box, in file order
  std::size_t dropped_empty = 0;         // rows dropped for zero / negative width or height
  std::size_t dropped_out_of_range = 0;  // rows dropped for |x|, |y|, w or h > kMaxBoxCoordinate
  int first_dropped_line = 0;            // line of the first dropped row, 0 when none
  std::size_t capped_frames = 0;         // frames that had more than kMaxBoxesPerFrame boxes
  std::size_t dropped_over_cap = 0;      // their least confident boxes beyond the cap, dropped
};

// The most boxes of one frame that are kept. A detector gives a few hundred at most; tens of thousands
// would make the per-frame box work (suppression, matching, the people filter) take minutes. Beyond it
// the most confident boxes are kept (file order among equal scores) and the rest counted and warned about.
constexpr std::size_t kMaxBoxesPerFrame = 2000;

// Reads a MOT file. `ground_truth` = parse columns 8-9 as class and visibility when the file has exactly
// 9 columns (MOT16/17); a 10-column file (MOT15: x, y, z world coordinates, -1 when unknown) is read
// with class -1. Throws InputError naming file and line. At most kMaxBoxesPerFrame boxes per frame.
MotFile read_mot_file(const std::string& path, bool ground_truth = false);

// Writes detections as MOT rows "frame,-1,x,y,w,h,conf,-1,-1,-1" (frame = frame_index + 1), atomically.
struct FrameBoxes {
  std::size_t frame_index = 0;  // 0-based
  std::vector<PersonBox> boxes;
};
void write_mot_detections(const std::string& path, const std::vector<FrameBoxes>& frames);

}  // namespace crowdslam::people
