#pragma once
// Per-level constants of an image scale pyramid (level 0 = original image).
#include <cmath>
#include <vector>

namespace crowdslam::map {

struct ScaleLevels {
  ScaleLevels() : ScaleLevels(1.2f, 8) {}
  ScaleLevels(float scale_factor_in, int num_levels_in)
      : scale_factor(scale_factor_in), num_levels(num_levels_in), log_scale_factor(std::log(scale_factor_in)) {
    scale.resize(num_levels);
    sigma2.resize(num_levels);
    inv_scale.resize(num_levels);
    inv_sigma2.resize(num_levels);
    float s = 1.0f;
    for (int i = 0; i < num_levels; ++i) {
      scale[i] = s;
      sigma2[i] = s * s;
      inv_scale[i] = 1.0f / s;
      inv_sigma2[i] = 1.0f / (s * s);
      s *= scale_factor;
    }
  }
  float scale_factor;
  int num_levels;
  float log_scale_factor;
  std::vector<float> scale;       // scale_factor^level
  std::vector<float> inv_scale;
  std::vector<float> sigma2;      // scale^2: variance of a keypoint's position at that level (px^2)
  std::vector<float> inv_sigma2;
};

}  // namespace crowdslam::map
