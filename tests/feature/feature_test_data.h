#pragma once
// Real frames for the feature tests (read from ../shared, never copied into the repository).
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "test_support.h"

namespace crowdslam::feature::testing {

// A Bonn crowd frame as 8-bit gray; empty if the data set is missing (tests skip first).
inline cv::Mat bonn_gray(const std::string& name = "1548339819.87426.jpg") {
  const auto path = crowdslam::test::shared_data("bonn_crowd") / "rgb" / name;
  return cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
}

}  // namespace crowdslam::feature::testing
