#pragma once
// TUM RGB-D / Bonn layout: DIR/rgb.txt, DIR/depth.txt (optional), DIR/groundtruth.txt (optional).
// Lists are "timestamp filename" with '#' comments; file names are relative to DIR (any extension).
// With depth.txt the sensor is RGB-D and the frames are the colour/depth pairs associated exactly as
// TUM's associate.py (|t_rgb - t_depth| < max_time_difference_s, greedy); without it the sensor is
// monocular and every colour entry is a frame. Frame stamps are colour stamps, in ascending order.
//
// Duplicated time stamps within one list are skipped with a warning, not an error: as TUM's scripts read
// lists into dicts, the later entry of equal stamps is used (so the evaluation and the run agree), and
// the count and the first repeated LIST:LINE are warned once. Every listed file must exist, the skipped
// ones too. When depth.txt exists but no colour/depth pair associates, opening is an error naming both
// lists (with their time spans). Unpaired entries of a normal sequence (a few colour images without a
// depth map within the window) are left out quietly, as associate.py does; `dataset info` shows both
// counts.
#include <memory>
#include <string>

#include "crowdslam/io/dataset.h"

namespace crowdslam::io {

bool looks_like_tum(const std::string& directory);
std::unique_ptr<Dataset> open_tum_dataset(const std::string& directory, const DatasetOptions& options = {});

}  // namespace crowdslam::io
