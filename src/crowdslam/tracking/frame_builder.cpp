#include "crowdslam/tracking/frame_builder.h"

#include <cassert>

#include "crowdslam/util/error.h"

namespace crowdslam::tracking {

void FrameBuilder::Options::check() const {
  orb.check();
  stereo.check();
  if (!(depth_map_factor > 0)) {
    throw InputError("DepthMapFactor must be > 0, got " + std::to_string(depth_map_factor));
  }
}

FrameBuilder::FrameBuilder(std::shared_ptr<const geometry::PinholeCamera> camera, const Options& options,
                           std::shared_ptr<const bow::Vocabulary> vocabulary)
    : camera_(std::move(camera)),
      options_(options),
      extractor_(options.orb),
      right_extractor_(options.orb),
      levels_(std::make_shared<map::ScaleLevels>(options.orb.scale_factor, options.orb.num_levels)),
      bounds_(camera_->undistorted_bounds()),
      vocabulary_(std::move(vocabulary)) {
  options_.check();
}

void FrameBuilder::extract(const cv::Mat& gray, int num_features, RawFeatures& out) {
  extractor_.extract(gray, num_features, out.keys, out.descriptors);
}

void FrameBuilder::extract(const feature::PreparedImage& prepared, int num_features, RawFeatures& out) {
  extractor_.extract(prepared, num_features, out.keys, out.descriptors);
}

std::shared_ptr<map::FrameFeatures> FrameBuilder::begin_features(RawFeatures&& raw) const {
  auto f = std::make_shared<map::FrameFeatures>();
  f->keys = std::move(raw.keys);
  f->descriptors = std::move(raw.descriptors);
  const size_t n = f->keys.size();

  std::vector<cv::Point2f> pixels(n);
  for (size_t i = 0; i < n; ++i) pixels[i] = f->keys[i].pt;
  const std::vector<cv::Point2f> undistorted = camera_->undistort_points(pixels);
  f->keys_un = f->keys;
  for (size_t i = 0; i < n; ++i) f->keys_un[i].pt = undistorted[i];
  return f;
}

void FrameBuilder::finish_features(map::FrameFeatures& f) const {
  f.grid = map::FeatureGrid(f.keys_un, bounds_);
  if (vocabulary_ && !vocabulary_->empty()) vocabulary_->transform(f.descriptors, f.bow, f.bow_features);
}

std::shared_ptr<map::FrameFeatures> FrameBuilder::assemble(RawFeatures&& raw, const cv::Mat& depth_raw) const {
  auto f = begin_features(std::move(raw));
  const size_t n = f->keys.size();
  f->depth_m.assign(n, -1.0f);
  f->right_u.assign(n, -1.0f);
  if (!depth_raw.empty()) {
    const float inv_factor = static_cast<float>(1.0 / options_.depth_map_factor);
    for (size_t i = 0; i < n; ++i) {
      // Depth is read at the raw (distorted) pixel: the depth image is registered to the raw colour image.
      const int x = cvRound(f->keys[i].pt.x);
      const int y = cvRound(f->keys[i].pt.y);
      if (x < 0 || y < 0 || x >= depth_raw.cols || y >= depth_raw.rows) continue;
      const uint16_t raw_depth = depth_raw.at<uint16_t>(y, x);
      if (raw_depth == 0) continue;
      const float depth = raw_depth * inv_factor;
      f->depth_m[i] = depth;
      f->right_u[i] = static_cast<float>(f->keys_un[i].pt.x - camera_->bf / depth);
    }
  }
  finish_features(*f);
  return f;
}

void FrameBuilder::extract_right(const cv::Mat& gray, int num_features, RawFeatures& out) {
  right_extractor_.extract(gray, num_features, out.keys, out.descriptors);
}

const StereoMatches& FrameBuilder::match_stereo(RawFeatures& left, const RawFeatures& right) {
  if (!camera_->is_stereo()) throw InputError("stereo needs Camera.bf > 0");
  if (!camera_->distortion.is_zero()) {
    throw InputError("stereo needs rectified images: Camera.k1/k2/p1/p2/k3 must be 0 (give LEFT/RIGHT blocks)");
  }
  if (!stereo_matcher_) {
    stereo_matcher_ = std::make_unique<StereoMatcher>(options_.stereo, *levels_, camera_->bf, camera_->fx);
  }
  const std::vector<cv::Mat>& left_pyramid = extractor_.pyramid();
  const std::vector<cv::Mat>& right_pyramid = right_extractor_.pyramid();
  assert(!left_pyramid.empty() && !right_pyramid.empty());
  if (left_pyramid[0].size() != right_pyramid[0].size()) {
    throw InputError("stereo pair of different sizes: left " + std::to_string(left_pyramid[0].cols) + "x" +
                     std::to_string(left_pyramid[0].rows) + ", right " + std::to_string(right_pyramid[0].cols) +
                     "x" + std::to_string(right_pyramid[0].rows));
  }
  stereo_matcher_->match(StereoView{left.keys, left.descriptors, left_pyramid},
                         StereoView{right.keys, right.descriptors, right_pyramid}, stereo_matches_);
  left.right_u = stereo_matches_.right_u;
  left.depth_m = stereo_matches_.depth_m;
  return stereo_matches_;
}

std::shared_ptr<map::FrameFeatures> FrameBuilder::assemble_stereo(RawFeatures&& left) const {
  assert(left.depth_m.size() == left.keys.size() && left.right_u.size() == left.keys.size());
  std::vector<float> right_u = std::move(left.right_u);
  std::vector<float> depth_m = std::move(left.depth_m);
  auto f = begin_features(std::move(left));
  const size_t n = f->keys.size();
  f->depth_m = std::move(depth_m);
  f->right_u.assign(n, -1.0f);
  for (size_t i = 0; i < n; ++i) {
    if (f->depth_m[i] <= 0) continue;
    // Rectified images: keys_un == keys, so the disparity carries over unchanged.
    const float disparity = f->keys[i].pt.x - right_u[i];
    f->right_u[i] = f->keys_un[i].pt.x - disparity;
  }
  finish_features(*f);
  return f;
}

}  // namespace crowdslam::tracking
