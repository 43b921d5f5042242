#pragma once
// The features of one image, computed once by tracking and then shared read-only by the frame and by the
// keyframe made from it (so keyframe creation copies nothing).
#include <opencv2/core.hpp>
#include <vector>

#include "crowdslam/bow/bow_vector.h"
#include "crowdslam/map/feature_grid.h"

namespace crowdslam::map {

struct FrameFeatures {
  std::vector<cv::KeyPoint> keys;     // as detected (distorted pixel coordinates), octave = pyramid level
  std::vector<cv::KeyPoint> keys_un;  // undistorted pixel coordinates
  std::vector<float> right_u;         // right-image u coordinate (stereo / virtual from depth); < 0 = none
  std::vector<float> depth_m;         // depth in metres; <= 0 = none
  cv::Mat descriptors;                // N x 32, CV_8UC1, row i belongs to keys[i]
  FeatureGrid grid;                   // over keys_un
  // Bag of words of the descriptors and its direct index (empty when no vocabulary is loaded).
  bow::BowVector bow;
  bow::FeatureVector bow_features;

  [[nodiscard]] bool has_bow() const { return !bow.empty(); }
  [[nodiscard]] size_t size() const { return keys_un.size(); }
  [[nodiscard]] bool has_right(size_t i) const { return !right_u.empty() && right_u[i] >= 0; }
  [[nodiscard]] const uint8_t* descriptor(size_t i) const { return descriptors.ptr<uint8_t>(static_cast<int>(i)); }
};

}  // namespace crowdslam::map
