// open_dataset / open_source: layout detection.
#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/euroc_dataset.h"
#include "crowdslam/io/image_folder_dataset.h"
#include "crowdslam/io/input_text.h"
#include "crowdslam/io/kitti_dataset.h"
#include "crowdslam/io/tum_dataset.h"
#include "crowdslam/io/video_dataset.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return ext;
}

// A text file: no NUL byte and (almost) only printable ASCII / UTF-8 and whitespace in its first 4 KiB.
// Videos are binary containers (their first bytes hold NULs), so this never refuses a video.
bool looks_like_text(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return false;
  std::array<unsigned char, 4096> head{};
  const std::size_t n = std::fread(head.data(), 1, head.size(), file);
  std::fclose(file);
  if (n == 0) return false;
  std::size_t odd = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char ch = head[i];
    if (ch == 0) return false;
    if (ch < 0x20 && ch != '\n' && ch != '\r' && ch != '\t') ++odd;
  }
  return odd * 100 <= n;  // <= 1 % control characters
}

// Refuses a list, settings or other text file given where a dataset directory or a video is expected:
// `--dataset DIR/rgb.txt` used to be opened as a video and fail obscurely.
void refuse_text_file(const std::string& spec) {
  static const char* const kTextExtensions[] = {".txt",  ".csv", ".yaml", ".yml",
                                                ".json", ".ini", ".md",   ".xml"};
  const std::string ext = lower_extension(spec);
  const bool text_extension = std::any_of(std::begin(kTextExtensions), std::end(kTextExtensions),
                                          [&](const char* e) { return ext == e; });
  if (!text_extension && !looks_like_text(spec)) return;
  std::error_code ec;
  fs::path parent = fs::absolute(spec, ec).parent_path();
  if (ec) parent = fs::path(spec).parent_path();
  const std::string name = fs::path(spec).filename().string();
  const bool list = ext == ".txt" || ext == ".csv";
  const std::string what = list ? "is a list file (" + clip_text(name) + "), not a dataset or a video"
                                : "is a text file, not a dataset directory or a video";
  std::string hint = "; pass the dataset directory (its parent, " + clip_text(parent.string()) + ") instead";
  if (ext == ".yaml" || ext == ".yml") hint += " (settings files go to --settings)";
  throw input_error(clip_text(spec), what + hint);
}

}  // namespace

std::unique_ptr<Dataset> open_dataset(const std::string& directory, const DatasetOptions& options) {
  options.check();
  std::error_code ec;
  const fs::file_status status = fs::status(directory, ec);
  if (status.type() == fs::file_type::not_found) throw input_error(clip_text(directory), "no such directory");
  if (ec) throw input_error(clip_text(directory), "cannot access: " + ec.message());
  if (!fs::is_directory(status)) throw input_error(clip_text(directory), "not a directory");
  if (looks_like_tum(directory)) return open_tum_dataset(directory, options);
  if (looks_like_euroc(directory)) return open_euroc_dataset(directory, options);
  if (looks_like_kitti(directory)) return open_kitti_dataset(directory, options);
  if (looks_like_image_folder(directory)) return open_image_folder_dataset(directory, options);
  throw input_error(clip_text(directory),
                    "unknown dataset layout (expected rgb.txt (TUM), mav0/cam0/data.csv (EuRoC), "
                    "times.txt + image_0/ (KITTI) or image files)");
}

std::unique_ptr<FrameSource> open_source(const std::string& spec, const DatasetOptions& options) {
  std::error_code ec;
  const bool all_digits =
      !spec.empty() && spec.size() < 4 &&
      std::all_of(spec.begin(), spec.end(), [](unsigned char ch) { return std::isdigit(ch); });
  const fs::file_status status = fs::status(spec, ec);
  if (all_digits && status.type() == fs::file_type::not_found)
    return VideoSource::open_camera(std::stoi(spec), options);
  if (status.type() == fs::file_type::not_found)
    throw input_error(clip_text(spec), "no such file or directory");
  if (ec) throw input_error(clip_text(spec), "cannot access: " + ec.message());
  if (fs::is_directory(status)) return open_dataset(spec, options);
  if (fs::is_regular_file(status)) {
    refuse_text_file(spec);
    return VideoSource::open_file(spec, options);
  }
  throw input_error(clip_text(spec), "not a directory, a video file or a camera index");
}

}  // namespace crowdslam::io
