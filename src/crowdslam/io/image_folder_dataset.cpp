#include "crowdslam/io/image_folder_dataset.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

std::vector<std::string> image_files(const std::string& directory) {
  std::vector<std::string> files;
  std::error_code ec;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file() && is_image_file_name(it->path().filename().string()))
      files.push_back(it->path().string());
  }
  if (ec) throw input_error(directory, "cannot list directory: " + ec.message());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

bool is_image_file_name(const std::string& name) {
  std::string ext = fs::path(name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  static const char* const kExtensions[] = {".png", ".jpg", ".jpeg", ".bmp", ".pgm", ".ppm", ".tif", ".tiff"};
  return std::any_of(std::begin(kExtensions), std::end(kExtensions), [&](const char* e) { return ext == e; });
}

bool looks_like_image_folder(const std::string& directory) { return !image_files(directory).empty(); }

std::unique_ptr<Dataset> open_image_folder_dataset(const std::string& directory,
                                                   const DatasetOptions& options) {
  options.check();
  const auto files = image_files(directory);
  if (files.empty()) throw input_error(directory, "no image files in folder");
  DatasetContents c;
  c.directory = directory;
  c.layout = "images";
  c.sensor = SensorKind::kMonocular;
  c.fps = options.fps > 0 ? options.fps : kDefaultImageFolderFps;
  for (std::size_t i = 0; i < files.size(); ++i)
    c.frames.push_back({i, static_cast<double>(i) / c.fps, files[i], {}, {}});
  c.colour_entries = files.size();
  return std::make_unique<Dataset>(std::move(c));
}

}  // namespace crowdslam::io
