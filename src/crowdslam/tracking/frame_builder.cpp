#include "crowdslam/tracking/frame_builder.h"

#include "crowdslam/util/error.h"

namespace crowdslam::tracking {

void FrameBuilder::Options::check() const {
  orb.check();
  if (!(depth_map_factor > 0)) {
    throw InputError("DepthMapFactor must be > 0, got " + std::to_string(depth_map_factor));
  }
}

FrameBuilder::FrameBuilder(std::shared_ptr<const geometry::PinholeCamera> camera, const Options& options,
                           std::shared_ptr<const bow::Vocabulary> vocabulary)
    : camera_(std::move(camera)),
      options_(options),
      extractor_(options.orb),
      levels_(std::make_shared<map::ScaleLevels>(options.orb.scale_factor, options.orb.num_levels)),
      bounds_(camera_->undistorted_bounds()),
      vocabulary_(std::move(vocabulary)) {
  options_.check();
}

void FrameBuilder::extract(const cv::Mat& gray, int num_features, RawFeatures& out) {
  extractor_.extract(gray, num_features, out.keys, out.descriptors);
}

std::shared_ptr<map::FrameFeatures> FrameBuilder::assemble(RawFeatures&& raw, const cv::Mat& depth_raw) const {
  auto f = std::make_shared<map::FrameFeatures>();
  f->keys = std::move(raw.keys);
  f->descriptors = std::move(raw.descriptors);
  const size_t n = f->keys.size();

  std::vector<cv::Point2f> pixels(n);
  for (size_t i = 0; i < n; ++i) pixels[i] = f->keys[i].pt;
  const std::vector<cv::Point2f> undistorted = camera_->undistort_points(pixels);
  f->keys_un = f->keys;
  for (size_t i = 0; i < n; ++i) f->keys_un[i].pt = undistorted[i];

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
  f->grid = map::FeatureGrid(f->keys_un, bounds_);
  if (vocabulary_ && !vocabulary_->empty()) vocabulary_->transform(f->descriptors, f->bow, f->bow_features);
  return f;
}

}  // namespace crowdslam::tracking
