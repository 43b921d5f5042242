#include "crowdslam/io/image_folder_dataset.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

// Entries with an image name: regular files are the frames; one that cannot be checked (a symlink loop,
// no permission) is an error naming it; other kinds (a folder called x.png, a dangling symlink) are
// skipped, counted and warned once when `warn`.
std::vector<std::string> image_files(const std::string& directory, bool warn) {
  std::vector<std::string> files;
  std::size_t skipped = 0;
  std::string first_skipped;
  std::error_code ec;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec)) {
    if (!is_image_file_name(it->path().filename().string())) continue;
    std::error_code entry_ec;
    const fs::file_status status = fs::status(it->path(), entry_ec);
    if (entry_ec && status.type() != fs::file_type::not_found)  // not found: a dangling symlink, skipped
      throw input_error(clip_text(it->path().string()), "cannot read image entry: " + entry_ec.message());
    if (fs::is_regular_file(status)) {
      files.push_back(it->path().string());
    } else if (skipped++ == 0) {
      first_skipped = it->path().string();
    }
  }
  if (ec) throw input_error(clip_text(directory), "cannot list directory: " + ec.message());
  if (warn && skipped > 0)
    spdlog::warn(
        "{}: {} entr{} with an image name but not a regular file (a folder, a dangling link) skipped",
        clip_text(first_skipped), skipped, skipped == 1 ? "y" : "ies");
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

bool looks_like_image_folder(const std::string& directory) { return !image_files(directory, false).empty(); }

std::unique_ptr<Dataset> open_image_folder_dataset(const std::string& directory,
                                                   const DatasetOptions& options) {
  options.check();
  const auto files = image_files(directory, true);
  if (files.empty()) throw input_error(clip_text(directory), "no image files in folder");
  DatasetContents c;
  c.directory = directory;
  c.layout = "images";
  c.same_size_frames = false;  // photos of any size (e.g. for vocabulary training)
  c.sensor = SensorKind::kMonocular;
  c.fps = options.fps > 0 ? options.fps : kDefaultImageFolderFps;
  for (std::size_t i = 0; i < files.size(); ++i)
    c.frames.push_back({i, static_cast<double>(i) / c.fps, files[i], {}, {}});
  c.colour_entries = files.size();
  return std::make_unique<Dataset>(std::move(c));
}

}  // namespace crowdslam::io
