#pragma once
// The ORB features of one image before they become a map::Frame (tracking::FrameBuilder): keypoints,
// descriptors and, for stereo, each keypoint's match in the right image. The people filter
// (people::PeopleStage) removes entries between extraction and assembly.
#include <opencv2/core.hpp>
#include <vector>

namespace crowdslam::feature {

struct RawFeatures {
  std::vector<cv::KeyPoint> keys;
  cv::Mat descriptors;
  // Stereo, after FrameBuilder::match_stereo(): per keypoint the right-image u and the depth (-1 = none).
  // Whoever drops keypoints (the people filter) drops their entries too.
  std::vector<float> right_u;
  std::vector<float> depth_m;
};

}  // namespace crowdslam::feature
