#include "crowdslam/io/euroc_dataset.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/core.hpp>

#include "crowdslam/io/dataset_ground_truth.h"
#include "crowdslam/io/dataset_list.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

fs::path mav0_of(const std::string& directory) {
  const fs::path dir(directory);
  if (fs::is_regular_file(dir / "mav0" / "cam0" / "data.csv")) return dir / "mav0";
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

// Full paths of a camera's list, checking each file exists; keyed by ns stamp.
std::map<long long, ListEntry> camera_entries(const fs::path& cam_dir, std::size_t& count) {
  const std::string list = (cam_dir / "data.csv").string();
  std::map<long long, ListEntry> entries;
  const auto rows = read_euroc_list(list);
  count = rows.size();
  for (auto row : rows) {
    row.file = (cam_dir / "data" / row.file).string();
    require_listed_file(row.file, list, row.line);
    entries[row.timestamp_ns] = row;
  }
  return entries;
}

}  // namespace

EurocCameraCalibration read_euroc_camera_calibration(const std::string& sensor_yaml) {
  if (!fs::is_regular_file(sensor_yaml)) throw input_error(sensor_yaml, "calibration file does not exist");
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
  return fs::is_regular_file(mav0_of(directory) / "cam0" / "data.csv");
}

std::unique_ptr<EurocDataset> open_euroc_dataset(const std::string& directory,
                                                 const DatasetOptions& options) {
  options.check();
  const fs::path mav0 = mav0_of(directory);
  DatasetContents c;
  c.directory = directory;
  c.layout = "euroc";
  const auto left = camera_entries(mav0 / "cam0", c.colour_entries);
  const auto left_calibration = read_euroc_camera_calibration((mav0 / "cam0" / "sensor.yaml").string());
  std::optional<EurocCameraCalibration> right_calibration;
  if (fs::exists(mav0 / "cam1" / "data.csv")) {
    c.sensor = SensorKind::kStereo;
    const auto right = camera_entries(mav0 / "cam1", c.right_entries);
    right_calibration = read_euroc_camera_calibration((mav0 / "cam1" / "sensor.yaml").string());
    for (const auto& [ns, entry] : left) {
      const auto match = right.find(ns);
      if (match != right.end())
        c.frames.push_back({c.frames.size(), entry.timestamp_s, entry.file, {}, match->second.file});
    }
    if (c.frames.empty())
      throw input_error((mav0 / "cam1" / "data.csv").string(), "no timestamp in common with cam0");
  } else {
    c.sensor = SensorKind::kMonocular;
    for (const auto& [ns, entry] : left)
      c.frames.push_back({c.frames.size(), entry.timestamp_s, entry.file, {}, {}});
  }
  const auto gt = mav0 / "state_groundtruth_estimate0" / "data.csv";
  if (fs::exists(gt)) {
    c.ground_truth_path = gt.string();
    c.ground_truth = load_euroc_ground_truth(c.ground_truth_path);
  }
  c.fps = left_calibration.rate_hz;
  return std::make_unique<EurocDataset>(std::move(c), left_calibration, right_calibration);
}

}  // namespace crowdslam::io
