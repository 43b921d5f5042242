#pragma once
// EuRoC MAV layout: DIR/mav0/cam0/{data.csv,data/,sensor.yaml}, DIR/mav0/cam1/... (optional: without it
// the sensor is monocular), DIR/mav0/state_groundtruth_estimate0/data.csv (optional). DIR may also be
// the mav0 folder itself. Stereo frames are the cam0/cam1 rows with identical ns stamps: left images
// without a right one (e.g. a cam1 list shorter than cam0's) are skipped with one warning giving the
// count and the first cam0 LINE; no common stamp at all is an error. Of rows with a duplicated ns stamp
// the later is used (warned once). Images are the raw (distorted, unrectified) ones; the parsed
// sensor.yaml calibration is exposed for rectification.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/io/dataset.h"

namespace crowdslam::io {

// One camera's sensor.yaml.
struct EurocCameraCalibration {
  std::array<double, 4> intrinsics{};  // fu, fv, cu, cv (pixels)
  std::string distortion_model;        // "radial-tangential" in EuRoC
  std::vector<double> distortion;      // k1, k2, p1, p2
  int width = 0;
  int height = 0;
  double rate_hz = 0.0;
  geometry::Mat4 body_from_sensor = geometry::Mat4::Identity();  // T_BS
};

// Throws InputError naming the file (and key) when missing or malformed.
EurocCameraCalibration read_euroc_camera_calibration(const std::string& sensor_yaml);

class EurocDataset : public Dataset {
 public:
  EurocDataset(DatasetContents contents, EurocCameraCalibration left,
               std::optional<EurocCameraCalibration> right)
      : Dataset(std::move(contents)), left_(std::move(left)), right_(std::move(right)) {}
  [[nodiscard]] const EurocCameraCalibration& left_calibration() const { return left_; }
  [[nodiscard]] const std::optional<EurocCameraCalibration>& right_calibration() const { return right_; }
  // right_from_left = inverse(T_BS right) * T_BS left; nullopt without cam1.
  [[nodiscard]] std::optional<geometry::Mat4> right_from_left() const;

 private:
  EurocCameraCalibration left_;
  std::optional<EurocCameraCalibration> right_;
};

bool looks_like_euroc(const std::string& directory);
std::unique_ptr<EurocDataset> open_euroc_dataset(const std::string& directory,
                                                 const DatasetOptions& options = {});

}  // namespace crowdslam::io
