#include "crowdslam/io/kitti_dataset.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include "crowdslam/io/dataset_ground_truth.h"
#include "crowdslam/io/dataset_list.h"
#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

std::string image_name(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu.png", index);
  return name;
}

// Projection matrices by name ("P0", "P1", ...), each 12 numbers.
std::map<std::string, std::vector<double>> read_projections(const std::string& path) {
  std::map<std::string, std::vector<double>> projections;
  const auto lines = read_lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (is_comment_or_blank(lines[i])) continue;
    const int line = static_cast<int>(i + 1);
    const auto fields = split_fields(lines[i], false);
    if (fields[0].empty() || fields[0].back() != ':')
      throw input_error(clip_text(path), line,
                        "expected 'NAME: numbers', got '" + clip_text(trim(lines[i])) + "'");
    const std::string name = fields[0].substr(0, fields[0].size() - 1);
    if (name.size() != 2 || name[0] != 'P') continue;  // Tr:, etc. are not needed
    if (fields.size() != 13)
      throw input_error(path, line, name + ": expected 12 numbers, got " + std::to_string(fields.size() - 1));
    std::vector<double> values;
    for (std::size_t k = 1; k < fields.size(); ++k) {
      const auto v = parse_double(fields[k]);
      if (!v || !std::isfinite(*v))
        throw input_error(clip_text(path), line,
                          name + ": '" + clip_text(fields[k]) + "' is not a finite number");
      values.push_back(*v);
    }
    projections[name] = values;
  }
  return projections;
}

bool regular_file_exists(const fs::path& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

bool directory_exists(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

fs::path ground_truth_path(const fs::path& dir) {
  std::error_code ec;
  const fs::path normal = fs::absolute(dir, ec).lexically_normal();
  if (!ec) {
    const fs::path sequence = normal.has_filename() ? normal : normal.parent_path();
    const fs::path official =
        sequence.parent_path().parent_path() / "poses" / (sequence.filename().string() + ".txt");
    if (regular_file_exists(official)) return official;
  }
  if (regular_file_exists(dir / "poses.txt")) return dir / "poses.txt";
  return {};
}

}  // namespace

KittiCalibration read_kitti_calibration(const std::string& calib_txt) {
  if (!regular_file_exists(calib_txt))
    throw input_error(clip_text(calib_txt), "calibration file does not exist");
  const auto projections = read_projections(calib_txt);
  const auto p0 = projections.find("P0");
  if (p0 == projections.end()) throw input_error(calib_txt, "no P0 line");
  KittiCalibration c;
  c.fx = p0->second[0];
  c.cx = p0->second[2];
  c.fy = p0->second[5];
  c.cy = p0->second[6];
  if (c.fx <= 0 || c.fy <= 0) throw input_error(calib_txt, "P0: focal length must be positive");
  if (const auto p1 = projections.find("P1"); p1 != projections.end()) c.bf = -p1->second[3];
  return c;
}

bool looks_like_kitti(const std::string& directory) {
  const fs::path dir(directory);
  return regular_file_exists(dir / "times.txt") && directory_exists(dir / "image_0");
}

std::unique_ptr<KittiDataset> open_kitti_dataset(const std::string& directory,
                                                 const DatasetOptions& options) {
  options.check();
  const fs::path dir(directory);
  DatasetContents c;
  c.directory = directory;
  c.layout = "kitti";
  const std::string times = (dir / "times.txt").string();
  const auto entries = read_times_list(times);
  std::vector<double> stamps;
  for (const auto& e : entries) stamps.push_back(e.timestamp_s);
  const bool stereo = directory_exists(dir / "image_1");
  c.sensor = stereo ? SensorKind::kStereo : SensorKind::kMonocular;
  const auto calibration = read_kitti_calibration((dir / "calib.txt").string());
  if (stereo && calibration.bf <= 0)
    throw input_error((dir / "calib.txt").string(), "P1: stereo needs a positive baseline (-P1[3] > 0)");
  for (std::size_t i = 0; i < stamps.size(); ++i) {
    const std::string left = (dir / "image_0" / image_name(i)).string();
    const std::string right = stereo ? (dir / "image_1" / image_name(i)).string() : std::string();
    const int line = entries[i].line;
    require_listed_file(left, times, line, options.missing_images_ok);
    if (stereo) require_listed_file(right, times, line, options.missing_images_ok);
    c.frames.push_back({i, stamps[i], left, {}, right});
  }
  c.colour_entries = stamps.size();
  c.right_entries = stereo ? stamps.size() : 0;
  if (const auto gt = ground_truth_path(dir); !gt.empty()) {
    c.ground_truth_path = gt.string();
    c.ground_truth = load_kitti_ground_truth(c.ground_truth_path, stamps);
  }
  return std::make_unique<KittiDataset>(std::move(c), calibration);
}

}  // namespace crowdslam::io
