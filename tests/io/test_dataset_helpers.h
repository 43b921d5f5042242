#pragma once
// Small hand-made datasets for the dataset reader tests.
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "test_support.h"

namespace crowdslam::test {

// A colour image whose pixel (0,0) encodes `value` (so tests can tell frames apart).
inline void write_colour(const std::filesystem::path& path, int value, cv::Size size = {8, 6}) {
  std::filesystem::create_directories(path.parent_path());
  cv::Mat image(size, CV_8UC3, cv::Scalar(10, 20, 30));
  image.at<cv::Vec3b>(0, 0) = cv::Vec3b(static_cast<uchar>(value), 0, 0);
  cv::imwrite(path.string(), image);
}

inline void write_grey(const std::filesystem::path& path, int value, cv::Size size = {8, 6}) {
  std::filesystem::create_directories(path.parent_path());
  cv::Mat image(size, CV_8UC1, cv::Scalar(50));
  image.at<uchar>(0, 0) = static_cast<uchar>(value);
  cv::imwrite(path.string(), image);
}

inline void write_depth(const std::filesystem::path& path, int value, cv::Size size = {8, 6}) {
  std::filesystem::create_directories(path.parent_path());
  cv::Mat image(size, CV_16UC1, cv::Scalar(value));
  cv::imwrite(path.string(), image);
}

// Cuts a file to half its size.
inline void truncate_half(const std::filesystem::path& path) {
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
}

// TUM layout: rgb/i.png + depth/i.png for the given stamps; groundtruth.txt with a pose per rgb stamp
// (tx = stamp).
inline void make_tum(const std::filesystem::path& dir, const std::vector<double>& rgb_stamps,
                     const std::vector<double>& depth_stamps, bool with_gt = true) {
  std::string rgb = "# color images\n# timestamp filename\n";
  for (std::size_t i = 0; i < rgb_stamps.size(); ++i) {
    const std::string name = "rgb/" + std::to_string(i) + ".png";
    write_colour(dir / name, static_cast<int>(i));
    rgb += std::to_string(rgb_stamps[i]) + " " + name + "\n";
  }
  write_text(dir / "rgb.txt", rgb);
  if (!depth_stamps.empty()) {
    std::string depth = "# depth maps\n";
    for (std::size_t i = 0; i < depth_stamps.size(); ++i) {
      const std::string name = "depth/" + std::to_string(i) + ".png";
      write_depth(dir / name, 1000 * static_cast<int>(i + 1));
      depth += std::to_string(depth_stamps[i]) + " " + name + "\n";
    }
    write_text(dir / "depth.txt", depth);
  }
  if (with_gt) {
    std::string gt = "# ground truth trajectory\n";
    for (const double t : rgb_stamps) gt += std::to_string(t) + " " + std::to_string(t) + " 0 0 0 0 0 1\n";
    write_text(dir / "groundtruth.txt", gt);
  }
}

}  // namespace crowdslam::test
