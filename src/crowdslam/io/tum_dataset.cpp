#include "crowdslam/io/tum_dataset.h"

#include <cstdio>
#include <filesystem>

#include "crowdslam/io/associate.h"
#include "crowdslam/io/dataset_ground_truth.h"
#include "crowdslam/io/dataset_list.h"
#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

std::vector<double> stamps_of(const std::vector<ListEntry>& entries) {
  std::vector<double> stamps;
  stamps.reserve(entries.size());
  for (const auto& e : entries) stamps.push_back(e.timestamp_s);
  return stamps;
}

// Every listed file must exist (even ones left unpaired): replaces each entry's name by its full path.
std::vector<ListEntry> resolved(const std::string& directory, std::vector<ListEntry> entries,
                                const std::string& list, bool missing_ok) {
  for (auto& entry : entries) {
    entry.file = (fs::path(directory) / entry.file).string();
    require_listed_file(entry.file, list, entry.line, missing_ok);
  }
  return entries;
}

// "a .. b" of an ascending list's stamps.
std::string span_of(const std::vector<ListEntry>& sorted) {
  char text[96];
  std::snprintf(text, sizeof(text), "%.6f .. %.6f", sorted.front().timestamp_s, sorted.back().timestamp_s);
  return text;
}

bool regular_file_exists(const fs::path& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

}  // namespace

bool looks_like_tum(const std::string& directory) {
  return regular_file_exists(fs::path(directory) / "rgb.txt");
}

std::unique_ptr<Dataset> open_tum_dataset(const std::string& directory, const DatasetOptions& options) {
  options.check();
  DatasetContents c;
  c.directory = directory;
  c.layout = "tum";
  const std::string rgb_list = (fs::path(directory) / "rgb.txt").string();
  const std::string depth_list = (fs::path(directory) / "depth.txt").string();
  const auto colour = resolved(directory, read_tum_list(rgb_list), rgb_list, options.missing_images_ok);
  c.colour_entries = colour.size();
  const auto colour_kept = without_duplicate_stamps(colour, rgb_list);
  std::error_code ec;
  if (fs::exists(depth_list, ec)) {
    c.sensor = SensorKind::kRgbd;
    const auto depth = resolved(directory, read_tum_list(depth_list), depth_list, options.missing_images_ok);
    c.depth_entries = depth.size();
    const auto depth_kept = without_duplicate_stamps(depth, depth_list);
    const auto pairs =
        associate_timestamps(stamps_of(colour_kept), stamps_of(depth_kept), options.max_time_difference_s);
    if (pairs.empty()) {
      char window[32];
      std::snprintf(window, sizeof(window), "%g", options.max_time_difference_s);
      throw input_error(clip_text(rgb_list), "no colour image has a depth map in " + clip_text(depth_list) +
                                               " within " + window + " s (colour stamps " +
                                               span_of(colour_kept) + ", depth stamps " +
                                               span_of(depth_kept) + "); nothing to run on");
    }
    for (const auto& pair : pairs) {
      const ListEntry& rgb = colour_kept[pair.first_index];
      const ListEntry& d = depth_kept[pair.second_index];
      c.frames.push_back({c.frames.size(), rgb.timestamp_s, rgb.file, d.file, {}});
    }
  } else {
    c.sensor = SensorKind::kMonocular;
    for (const auto& rgb : colour_kept)
      c.frames.push_back({c.frames.size(), rgb.timestamp_s, rgb.file, {}, {}});
  }
  const auto gt = fs::path(directory) / "groundtruth.txt";
  if (fs::exists(gt, ec)) {
    c.ground_truth_path = gt.string();
    c.ground_truth = load_tum_ground_truth(c.ground_truth_path);
  }
  return std::make_unique<Dataset>(std::move(c));
}

}  // namespace crowdslam::io
