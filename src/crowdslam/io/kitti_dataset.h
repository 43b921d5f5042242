#pragma once
// KITTI odometry layout: DIR/image_0/%06d.png (left), DIR/image_1/%06d.png (right, optional: without it
// the sensor is monocular), DIR/times.txt (one stamp per frame, defines the frame count), DIR/calib.txt
// ("P0: 12 numbers", "P1: ..."). Ground truth (optional): DIR/../../poses/<name of DIR>.txt (official
// layout: dataset/sequences/00 -> dataset/poses/00.txt) or DIR/poses.txt (our synthetic generator),
// 12 numbers per line (row-major 3x4 world_from_cam), stamps taken from times.txt.
#include <memory>
#include <string>

#include "crowdslam/io/dataset.h"

namespace crowdslam::io {

// From the rectified projection matrices P0 (left) and P1 (right).
struct KittiCalibration {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  double bf = 0.0;  // baseline * fx = -P1[3] (0 without P1)
};

// Throws InputError naming the file and line (or the missing P0).
KittiCalibration read_kitti_calibration(const std::string& calib_txt);

class KittiDataset : public Dataset {
 public:
  KittiDataset(DatasetContents contents, KittiCalibration calibration)
      : Dataset(std::move(contents)), calibration_(calibration) {}
  [[nodiscard]] const KittiCalibration& calibration() const { return calibration_; }

 private:
  KittiCalibration calibration_;
};

bool looks_like_kitti(const std::string& directory);
std::unique_ptr<KittiDataset> open_kitti_dataset(const std::string& directory,
                                                 const DatasetOptions& options = {});

}  // namespace crowdslam::io
