// open_dataset / open_source: layout detection.
#include <algorithm>
#include <cctype>
#include <filesystem>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/euroc_dataset.h"
#include "crowdslam/io/image_folder_dataset.h"
#include "crowdslam/io/kitti_dataset.h"
#include "crowdslam/io/tum_dataset.h"
#include "crowdslam/io/video_dataset.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;

std::unique_ptr<Dataset> open_dataset(const std::string& directory, const DatasetOptions& options) {
  options.check();
  std::error_code ec;
  if (!fs::exists(directory, ec)) throw input_error(directory, "no such directory");
  if (!fs::is_directory(directory, ec)) throw input_error(directory, "not a directory");
  if (looks_like_tum(directory)) return open_tum_dataset(directory, options);
  if (looks_like_euroc(directory)) return open_euroc_dataset(directory, options);
  if (looks_like_kitti(directory)) return open_kitti_dataset(directory, options);
  if (looks_like_image_folder(directory)) return open_image_folder_dataset(directory, options);
  throw input_error(directory,
                    "unknown dataset layout (expected rgb.txt (TUM), mav0/cam0/data.csv (EuRoC), "
                    "times.txt + image_0/ (KITTI) or image files)");
}

std::unique_ptr<FrameSource> open_source(const std::string& spec, const DatasetOptions& options) {
  std::error_code ec;
  const bool all_digits =
      !spec.empty() && spec.size() < 4 &&
      std::all_of(spec.begin(), spec.end(), [](unsigned char ch) { return std::isdigit(ch); });
  if (all_digits && !fs::exists(spec, ec)) return VideoSource::open_camera(std::stoi(spec), options);
  if (fs::is_directory(spec, ec)) return open_dataset(spec, options);
  if (fs::is_regular_file(spec, ec)) return VideoSource::open_file(spec, options);
  throw input_error(spec, "no such file or directory");
}

}  // namespace crowdslam::io
