#pragma once
// Turns an image (and depth for RGB-D, or the right image for stereo) into the features of a map::Frame,
// in two steps so that the people filter can run in between: extract() gives raw ORB keypoints and
// descriptors; assemble() undistorts the kept ones, attaches depth and the virtual right coordinate, and
// builds the search grid.
//
// Stereo (rectified pair): extract() for the left image and extract_right() for the right one use two
// extractors, so they may run on two threads at once; match_stereo() then matches the left keypoints
// along rows against the right ones (StereoMatcher) using both extractors' pyramids, which stay valid
// until the next extract()/extract_right() as long as the caller keeps the grey images alive. Matching
// comes before the people filter so that its depth mode has the keypoints' depths; assemble_stereo()
// builds the frame from the kept keypoints and their matches.
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/feature/raw_features.h"
#include "crowdslam/geometry/camera.h"
#include "crowdslam/map/frame_features.h"
#include "crowdslam/map/scale_levels.h"
#include "crowdslam/tracking/stereo_matcher.h"

namespace crowdslam::tracking {

using feature::RawFeatures;

class FrameBuilder {
 public:
  struct Options {
    feature::ORBExtractor::Options orb;
    double depth_map_factor = 5000.0;  // raw depth value per metre (RGB-D)
    StereoMatcherOptions stereo;       // stereo only
    void check() const;
  };

  // With a vocabulary, assemble() also computes each frame's bag of words and direct index.
  FrameBuilder(std::shared_ptr<const geometry::PinholeCamera> camera, const Options& options,
               std::shared_ptr<const bow::Vocabulary> vocabulary = nullptr);

  void extract(const cv::Mat& gray, int num_features, RawFeatures& out);
  // The same from what an extractor with these options prepared (feature::ORBExtractor::prepare).
  void extract(const feature::PreparedImage& prepared, int num_features, RawFeatures& out);
  [[nodiscard]] const feature::ORBExtractor::Options& orb_options() const { return extractor_.options(); }
  // depth_raw: CV_16UC1 raw depth (0 = none) of the same size as the image, or empty (monocular).
  [[nodiscard]] std::shared_ptr<map::FrameFeatures> assemble(RawFeatures&& raw, const cv::Mat& depth_raw) const;

  // Stereo: ORB on the right image (same size as the left one) with the right extractor.
  void extract_right(const cv::Mat& gray, int num_features, RawFeatures& out);
  // Stereo: fills left.right_u and left.depth_m. `left` from the last extract(), `right` from the last
  // extract_right(). Needs a camera with bf > 0 and no distortion (rectified images); throws InputError
  // otherwise or when the two images differ in size.
  const StereoMatches& match_stereo(RawFeatures& left, const RawFeatures& right);
  // Stereo: the frame from matched (possibly filtered) left features.
  [[nodiscard]] std::shared_ptr<map::FrameFeatures> assemble_stereo(RawFeatures&& left) const;
  // Both steps at once (no filter in between).
  [[nodiscard]] std::shared_ptr<map::FrameFeatures> assemble_stereo(RawFeatures&& left, const RawFeatures& right) {
    match_stereo(left, right);
    return assemble_stereo(std::move(left));
  }
  // Statistics of the last match_stereo().
  [[nodiscard]] const StereoMatches& last_stereo_matches() const { return stereo_matches_; }

  [[nodiscard]] const std::shared_ptr<const map::ScaleLevels>& levels() const { return levels_; }
  [[nodiscard]] const std::shared_ptr<const geometry::PinholeCamera>& camera() const { return camera_; }
  [[nodiscard]] int default_num_features() const { return options_.orb.num_features; }
  [[nodiscard]] double depth_map_factor() const { return options_.depth_map_factor; }  // raw units per metre

 private:
  std::shared_ptr<const geometry::PinholeCamera> camera_;
  Options options_;
  [[nodiscard]] std::shared_ptr<map::FrameFeatures> begin_features(RawFeatures&& raw) const;
  void finish_features(map::FrameFeatures& f) const;

  feature::ORBExtractor extractor_;
  feature::ORBExtractor right_extractor_;
  std::shared_ptr<const map::ScaleLevels> levels_;
  std::unique_ptr<StereoMatcher> stereo_matcher_;  // created on first use (camera must be stereo)
  StereoMatches stereo_matches_;
  geometry::ImageBounds bounds_;
  std::shared_ptr<const bow::Vocabulary> vocabulary_;
};

}  // namespace crowdslam::tracking
