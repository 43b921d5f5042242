#include "crowdslam/io/euroc_dataset.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/core.hpp>

#include "crowdslam/io/dataset_ground_truth.h"
#include "crowdslam/io/dataset_list.h"
#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

bool regular_file_exists(const fs::path& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

fs::path mav0_of(const std::string& directory) {
  const fs::path dir(directory);
  if (regular_file_exists(dir / "mav0" / "cam0" / "data.csv")) return dir / "mav0";
  return dir;
}

std::vector<double> numbers_of(const cv::FileNode& node, const std::string& path, const std::string& key,
                               std::size_t count) {  // count 0 = any non-empty list
  if (node.empty() || !node.isSeq() || node.size() == 0 || (count != 0 && node.size() != count))
    throw input_error(path, key + ": expected a list of " +
                                (count ? std::to_string(count) + " " : std::string()) + "numbers");
  std::vector<double> values;
  for (const auto& item : node) {
    if (!item.isReal() && !item.isInt()) throw input_error(path, key + ": expected numbers");
    values.push_back(static_cast<double>(item));
    if (!std::isfinite(values.back())) throw input_error(path, key + ": value is not finite");
  }
  return values;
}

EurocCameraCalibration parse_calibration(const cv::FileStorage& fs, const std::string& path) {
  EurocCameraCalibration c;
  const auto in = numbers_of(fs["intrinsics"], path, "intrinsics", 4);
  for (int i = 0; i < 4; ++i) c.intrinsics[i] = in[i];
  if (in[0] <= 0 || in[1] <= 0) throw input_error(path, "intrinsics: focal lengths must be positive");
  c.distortion = numbers_of(fs["distortion_coefficients"], path, "distortion_coefficients", 0);
  if (fs["distortion_model"].isString())
    c.distortion_model = static_cast<std::string>(fs["distortion_model"]);
  const auto resolution = numbers_of(fs["resolution"], path, "resolution", 2);
  c.width = static_cast<int>(resolution[0]);
  c.height = static_cast<int>(resolution[1]);
  if (c.width <= 0 || c.height <= 0) throw input_error(path, "resolution: must be positive");
  if (!fs["rate_hz"].empty()) c.rate_hz = static_cast<double>(fs["rate_hz"]);
  const auto t = numbers_of(fs["T_BS"]["data"], path, "T_BS.data", 16);
  for (int r = 0; r < 4; ++r)
    for (int col = 0; col < 4; ++col) c.body_from_sensor(r, col) = t[4 * r + col];
  return c;
}

// Full paths of a camera's list, checking each file exists; keyed by ns stamp (of duplicated stamps the
// later row wins, warned once).
std::map<long long, ListEntry> camera_entries(const fs::path& cam_dir, std::size_t& count, bool missing_ok) {
  const std::string list = (cam_dir / "data.csv").string();
  auto rows = read_euroc_list(list);
  count = rows.size();
  for (auto& row : rows) {
    row.file = (cam_dir / "data" / row.file).string();
    require_listed_file(row.file, list, row.line, missing_ok);
  }
  std::map<long long, ListEntry> entries;
  for (auto& row : without_duplicate_stamps(rows, list, true))
    entries.emplace(row.timestamp_ns, std::move(row));
  return entries;
}

// Left images without a right image of the same stamp are skipped: counted and warned once, with the
// first such cam0 row (and the right-only count).
void warn_unpaired(const std::map<long long, ListEntry>& left, const std::map<long long, ListEntry>& right,
                   const fs::path& mav0) {
  std::size_t left_only = 0;
  int first_line = 0;
  for (const auto& [ns, entry] : left) {
    if (right.count(ns)) continue;
    if (left_only++ == 0) first_line = entry.line;
  }
  std::size_t right_only = 0;
  for (const auto& [ns, entry] : right) right_only += left.count(ns) ? 0 : 1;
  if (left_only == 0 && right_only == 0) return;
  const std::string left_list = clip_text((mav0 / "cam0" / "data.csv").string());
  const std::string right_list = clip_text((mav0 / "cam1" / "data.csv").string());
  if (left_only > 0) {
    spdlog::warn(
        "{}:{}: {} of {} left images have no right image with the same time stamp in {}; stereo skips "
        "them ({} right image(s) without a left one)",
        left_list, first_line, left_only, left.size(), right_list, right_only);
  } else {
    spdlog::warn(
        "{}: {} of {} right images have no left image with the same time stamp in {}; stereo skips them",
        right_list, right_only, right.size(), left_list);
  }
}

}  // namespace

EurocCameraCalibration read_euroc_camera_calibration(const std::string& sensor_yaml) {
  if (!regular_file_exists(sensor_yaml))
    throw input_error(clip_text(sensor_yaml), "calibration file does not exist");
  try {
    cv::FileStorage storage(sensor_yaml, cv::FileStorage::READ);
    if (!storage.isOpened()) throw input_error(sensor_yaml, "cannot open calibration file");
    return parse_calibration(storage, sensor_yaml);
  } catch (const cv::Exception& e) {
    throw input_error(sensor_yaml, std::string("cannot parse calibration: ") + e.what());
  }
}

std::optional<geometry::Mat4> EurocDataset::right_from_left() const {
  if (!right_) return std::nullopt;
  return geometry::Mat4(right_->body_from_sensor.inverse() * left_.body_from_sensor);
}

bool looks_like_euroc(const std::string& directory) {
  return regular_file_exists(mav0_of(directory) / "cam0" / "data.csv");
}

std::unique_ptr<EurocDataset> open_euroc_dataset(const std::string& directory,
                                                 const DatasetOptions& options) {
  options.check();
  const fs::path mav0 = mav0_of(directory);
  DatasetContents c;
  c.directory = directory;
  c.layout = "euroc";
  const auto left = camera_entries(mav0 / "cam0", c.colour_entries, options.missing_images_ok);
  const auto left_calibration = read_euroc_camera_calibration((mav0 / "cam0" / "sensor.yaml").string());
  std::optional<EurocCameraCalibration> right_calibration;
  std::error_code ec;
  if (fs::exists(mav0 / "cam1" / "data.csv", ec)) {
    c.sensor = SensorKind::kStereo;
    const auto right = camera_entries(mav0 / "cam1", c.right_entries, options.missing_images_ok);
    right_calibration = read_euroc_camera_calibration((mav0 / "cam1" / "sensor.yaml").string());
    for (const auto& [ns, entry] : left) {
      const auto match = right.find(ns);
      if (match != right.end())
        c.frames.push_back({c.frames.size(), entry.timestamp_s, entry.file, {}, match->second.file});
    }
    if (c.frames.empty())
      throw input_error(clip_text((mav0 / "cam1" / "data.csv").string()), "no timestamp in common with cam0");
    warn_unpaired(left, right, mav0);
  } else {
    c.sensor = SensorKind::kMonocular;
    for (const auto& [ns, entry] : left)
      c.frames.push_back({c.frames.size(), entry.timestamp_s, entry.file, {}, {}});
  }
  const auto gt = mav0 / "state_groundtruth_estimate0" / "data.csv";
  if (fs::exists(gt, ec)) {
    c.ground_truth_path = gt.string();
    c.ground_truth = load_euroc_ground_truth(c.ground_truth_path);
  }
  c.fps = left_calibration.rate_hz;
  return std::make_unique<EurocDataset>(std::move(c), left_calibration, right_calibration);
}

}  // namespace crowdslam::io
