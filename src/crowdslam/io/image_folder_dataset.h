#pragma once
// A folder of images (monocular): every file with an image extension (png, jpg, jpeg, bmp, pgm, ppm, tif,
// tiff; any case), sorted by name; frame i has timestamp i / fps (DatasetOptions::fps, default 30).
// No ground truth. Images may differ in size (Dataset::load does not compare them with the first).
// An entry with an image name that cannot be checked (a symlink loop) is an error naming it; one that
// is not a regular file (a folder, a dangling symlink) is skipped with one warning.
#include <memory>
#include <string>

#include "crowdslam/io/dataset.h"

namespace crowdslam::io {

constexpr double kDefaultImageFolderFps = 30.0;

bool is_image_file_name(const std::string& name);
bool looks_like_image_folder(const std::string& directory);
std::unique_ptr<Dataset> open_image_folder_dataset(const std::string& directory,
                                                   const DatasetOptions& options = {});

}  // namespace crowdslam::io
