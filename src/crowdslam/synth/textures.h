#pragma once
// Surface textures of the synthetic scene: photo collages (Debian's opencv-doc sample photographs) or,
// when those are absent, procedural noise-and-shapes images; clothing-like textures for people.
// Every texture is a mip pyramid sampled trilinearly so that distant surfaces do not alias.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "crowdslam/synth/rng.h"

namespace crowdslam::synth {

constexpr double kTexelsPerMetre = 300.0;

class Texture {
 public:
  Texture() = default;
  // image: CV_8UC3 BGR. Builds the pyramid.
  explicit Texture(const cv::Mat& image);

  // Trilinear sample at level-0 texel coordinates (texel centres at integers), clamped at the border.
  // lod = log2(texels per pixel); <= 0 means plain bilinear at level 0.
  cv::Vec3f sample(double s, double t, double lod) const;
  int width() const { return levels_.empty() ? 0 : levels_[0].cols; }
  int height() const { return levels_.empty() ? 0 : levels_[0].rows; }
  const cv::Mat& image() const { return levels_[0]; }

 private:
  cv::Vec3f bilinear(int level, double s, double t) const;
  std::vector<cv::Mat> levels_;
};

// Loads the sample photographs that exist in `dir` in a fixed order (missing ones are skipped; an empty
// dir or one without photos gives an empty list).
std::vector<cv::Mat> load_photos(const std::string& dir);

// A wall/floor texture of the given size in texels: rows of photo crops (or procedural tiles when
// `photos` is empty), chosen by `rng`.
cv::Mat make_collage(int width, int height, Rng& rng, const std::vector<cv::Mat>& photos);

// A procedural tile: multi-octave value noise in two colours plus random rectangles, discs and lines.
cv::Mat make_procedural_tile(int width, int height, Rng& rng);

// A person's texture wrapped around its body: head (skin, hair) on top, striped/noisy shirt, dark
// trousers. `width` is the body perimeter, `height` the body height, both in texels.
cv::Mat make_clothing(int width, int height, Rng& rng);

}  // namespace crowdslam::synth
