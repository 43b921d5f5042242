#pragma once
// Helpers shared by the synth tests: reprojection consistency between two frames.
#include <filesystem>
#include <opencv2/core.hpp>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/synth/options.h"

namespace crowdslam::synth::test {

struct Consistency {
  int sampled = 0;         // pixels of frame i with depth (not on people)
  int inside = 0;          // ... that project inside frame j, in front of it
  int depth_agrees = 0;    // ... whose predicted depth matches frame j's depth within 1%
  double median_grey_diff = 255.0;  // over the depth-agreeing pixels (not on people in j either)
};

// Back-projects every `step`-th pixel of frame i with its depth, moves it into frame j with the poses,
// compares depth (nearest pixel) and colour (bilinear) there. Labels may be empty (no people).
Consistency check_consistency(const cv::Mat& colour_i, const cv::Mat& depth_i, const cv::Mat& label_i,
                              const geometry::SE3& world_from_i, const cv::Mat& colour_j, const cv::Mat& depth_j,
                              const cv::Mat& label_j, const geometry::SE3& world_from_j, const Intrinsics& k,
                              int step = 2);

// Writes `count` procedural person sprites and their sprites.json into `dir` (created): 60 x 160 px BGRA,
// a head, a torso with arms and two legs with a gap between them, each sprite its own colours, facing
// +1 (the photographed person walked right). `opaque_rectangles`: every texel opaque instead.
void write_test_sprites(const std::filesystem::path& dir, int count, bool opaque_rectangles = false);

// The person shape of write_test_sprites: opaque at texel (x, y) of a 60 x 160 sprite.
bool test_sprite_opaque(int x, int y);

}  // namespace crowdslam::synth::test
