#include "crowdslam/io/tum_dataset.h"

#include <filesystem>

#include "crowdslam/io/associate.h"
#include "crowdslam/io/dataset_ground_truth.h"
#include "crowdslam/io/dataset_list.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

std::vector<double> stamps_of(const std::vector<ListEntry>& entries) {
  std::vector<double> stamps;
  stamps.reserve(entries.size());
  for (const auto& e : entries) stamps.push_back(e.timestamp_s);
  return stamps;
}

// Entries kept when read into a dict (last duplicate wins), ascending by stamp.
std::vector<ListEntry> deduped(const std::vector<ListEntry>& entries) {
  std::vector<ListEntry> kept;
  for (const std::size_t i : dedupe_last_wins(stamps_of(entries))) kept.push_back(entries[i]);
  return kept;
}

// Every listed file must exist (even ones left unpaired): replaces each entry's name by its full path.
std::vector<ListEntry> resolved(const std::string& directory, std::vector<ListEntry> entries,
                                const std::string& list) {
  for (auto& entry : entries) {
    entry.file = (fs::path(directory) / entry.file).string();
    require_listed_file(entry.file, list, entry.line);
  }
  return entries;
}

}  // namespace

bool looks_like_tum(const std::string& directory) {
  return fs::is_regular_file(fs::path(directory) / "rgb.txt");
}

std::unique_ptr<Dataset> open_tum_dataset(const std::string& directory, const DatasetOptions& options) {
  options.check();
  DatasetContents c;
  c.directory = directory;
  c.layout = "tum";
  const std::string rgb_list = (fs::path(directory) / "rgb.txt").string();
  const std::string depth_list = (fs::path(directory) / "depth.txt").string();
  const auto colour = resolved(directory, read_tum_list(rgb_list), rgb_list);
  c.colour_entries = colour.size();
  if (fs::exists(depth_list)) {
    c.sensor = SensorKind::kRgbd;
    const auto depth = resolved(directory, read_tum_list(depth_list), depth_list);
    c.depth_entries = depth.size();
    const auto colour_kept = deduped(colour);
    const auto depth_kept = deduped(depth);
    const auto pairs =
        associate_timestamps(stamps_of(colour_kept), stamps_of(depth_kept), options.max_time_difference_s);
    for (const auto& pair : pairs) {
      const ListEntry& rgb = colour_kept[pair.first_index];
      const ListEntry& d = depth_kept[pair.second_index];
      c.frames.push_back({c.frames.size(), rgb.timestamp_s, rgb.file, d.file, {}});
    }
  } else {
    c.sensor = SensorKind::kMonocular;
    for (const auto& rgb : colour) c.frames.push_back({c.frames.size(), rgb.timestamp_s, rgb.file, {}, {}});
  }
  const auto gt = fs::path(directory) / "groundtruth.txt";
  if (fs::exists(gt)) {
    c.ground_truth_path = gt.string();
    c.ground_truth = load_tum_ground_truth(c.ground_truth_path);
  }
  return std::make_unique<Dataset>(std::move(c));
}

}  // namespace crowdslam::io
