#pragma once
// Blacks out frames [first, last) of an image folder (NNNNNN.png names, as the synthetic generator
// writes them): a camera that sees nothing there. Returns how many images were blanked.
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace crowdslam::test {

inline int blank_frames(const std::filesystem::path& folder, int first, int last) {
  int blanked = 0;
  for (const auto& e : std::filesystem::directory_iterator(folder)) {
    const int index = std::stoi(e.path().stem().string());
    if (index < first || index >= last) continue;
    cv::Mat image = cv::imread(e.path().string(), cv::IMREAD_UNCHANGED);
    image.setTo(cv::Scalar::all(0));
    cv::imwrite(e.path().string(), image);
    ++blanked;
  }
  return blanked;
}

}  // namespace crowdslam::test
