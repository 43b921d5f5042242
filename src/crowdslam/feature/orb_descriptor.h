#pragma once
// Keypoint orientation (intensity centroid) and the steered BRIEF descriptor of ORB, for one pyramid level.
// Both read a patch around the keypoint: callers keep keypoints at least kOrbEdgeThreshold pixels inside
// the level image (the extractor guarantees this); closer points are a programming error (assert).
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>

namespace crowdslam::feature {

inline constexpr int kOrbPatchSize = 31;                 // BRIEF / orientation patch diameter
inline constexpr int kOrbHalfPatch = kOrbPatchSize / 2;  // 15: orientation circle radius
inline constexpr int kOrbEdgeThreshold = 19;             // keypoints stay this far from level borders

// Half-width of the circular orientation patch per row offset v = 0..15 (|u| <= half_width[|v|]); the
// table is symmetric under swapping u and v.
const std::array<int, kOrbHalfPatch + 1>& circle_half_widths();

// Orientation of the intensity centroid of the circular patch (radius 15) around the pixel nearest to
// `pt`, in degrees in [0, 360): atan2(m01, m10) with image axes x right, y down. `image` is CV_8UC1.
float intensity_centroid_angle(const cv::Mat& image, cv::Point2f pt);

// 256-bit steered BRIEF with the standard ORB pattern rotated by `angle_deg`, sampled around the pixel
// nearest to `pt` of `blurred` (CV_8UC1, the level image after a 7x7, sigma 2 Gaussian blur). Writes
// 32 bytes to `descriptor`; bit j of byte i is test 8i+j. Identical to cv::ORB for the same inputs.
void steered_brief(const cv::Mat& blurred, cv::Point2f pt, float angle_deg, std::uint8_t* descriptor);

}  // namespace crowdslam::feature
