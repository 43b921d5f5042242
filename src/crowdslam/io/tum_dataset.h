#pragma once
// TUM RGB-D / Bonn layout: DIR/rgb.txt, DIR/depth.txt (optional), DIR/groundtruth.txt (optional).
// Lists are "timestamp filename" with '#' comments; file names are relative to DIR (any extension).
// With depth.txt the sensor is RGB-D and the frames are the colour/depth pairs associated exactly as
// TUM's associate.py (duplicate stamps: last wins; |t_rgb - t_depth| < max_time_difference_s, greedy);
// without it the sensor is monocular and every colour entry is a frame. Frame stamps are colour stamps.
#include <memory>
#include <string>

#include "crowdslam/io/dataset.h"

namespace crowdslam::io {

bool looks_like_tum(const std::string& directory);
std::unique_ptr<Dataset> open_tum_dataset(const std::string& directory, const DatasetOptions& options = {});

}  // namespace crowdslam::io
