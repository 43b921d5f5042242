#pragma once
// Turns an image (and depth for RGB-D) into the features of a map::Frame, in two steps so that the people
// filter can run in between: extract() gives raw ORB keypoints and descriptors; assemble() undistorts the
// kept ones, attaches depth and the virtual right coordinate, and builds the search grid.
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/geometry/camera.h"
#include "crowdslam/map/frame_features.h"
#include "crowdslam/map/scale_levels.h"

namespace crowdslam::tracking {

struct RawFeatures {
  std::vector<cv::KeyPoint> keys;
  cv::Mat descriptors;
};

class FrameBuilder {
 public:
  struct Options {
    feature::ORBExtractor::Options orb;
    double depth_map_factor = 5000.0;  // raw depth value per metre (RGB-D)
    void check() const;
  };

  // With a vocabulary, assemble() also computes each frame's bag of words and direct index.
  FrameBuilder(std::shared_ptr<const geometry::PinholeCamera> camera, const Options& options,
               std::shared_ptr<const bow::Vocabulary> vocabulary = nullptr);

  void extract(const cv::Mat& gray, int num_features, RawFeatures& out);
  // depth_raw: CV_16UC1 raw depth (0 = none) of the same size as the image, or empty (monocular).
  [[nodiscard]] std::shared_ptr<map::FrameFeatures> assemble(RawFeatures&& raw, const cv::Mat& depth_raw) const;

  [[nodiscard]] const std::shared_ptr<const map::ScaleLevels>& levels() const { return levels_; }
  [[nodiscard]] const std::shared_ptr<const geometry::PinholeCamera>& camera() const { return camera_; }
  [[nodiscard]] int default_num_features() const { return options_.orb.num_features; }

 private:
  std::shared_ptr<const geometry::PinholeCamera> camera_;
  Options options_;
  feature::ORBExtractor extractor_;
  std::shared_ptr<const map::ScaleLevels> levels_;
  geometry::ImageBounds bounds_;
  std::shared_ptr<const bow::Vocabulary> vocabulary_;
};

}  // namespace crowdslam::tracking
