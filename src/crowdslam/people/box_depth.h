#pragma once
// Does a person box hold something that stands in front of its surroundings?
//
// A person is a solid object in front of what is around them; a detector firing on a poster, a wall
// photograph or a screen boxes a surface that continues past the box. With a depth image that is
// measurable: the depth of the box's torso region (35-65 % of its width, 20-55 % of its height, median)
// against planes fitted in inverse depth (exact for a planar surface: 1/z is affine in the pixel) to the
// median depths of patches just outside the box (a quarter of the box's width to its left and right, at
// three heights; an eighth of its height above it, two halves): one plane through each pair of sides and
// one through all three. If the torso is not closer than any of these planes by more than `margin_m`, the
// box is flat: nothing stands out of the surface it was found on. (A person beside a crate or another
// person, one side as close as they are, still stands out against the pair of the other sides.)
// A box at the image's left or right edge with fewer than two sides outside it is judged on strips inside
// both its edges. A close person cut by the image's edge fills their box, so those strips may show only
// them: a box at one side edge also stands out where rows through its torso meet an occluding edge (a
// step in depth from the torso's surface to something behind it) towards the side it has outside it.
// Undecidable (kUnknown) without depth, or with too little depth around the box; those boxes are kept
// as they are.
// In a crowd the patches beside a person often show other people, as close as they are. A box found flat
// with a patch whose centre lies in another person's box (`other_people`; boxes overlapping `box` by
// IoU >= 0.5 are the same detection and ignored) and that is not behind the torso by more than the
// margin is judged again without those patches: on the background they stand in front of, or left
// undecided, never flat on their neighbours alone (nor, at the image's edge,
// on the strips inside their own box, which among people show people). Without this, every box
// of a crowd covering the view was flat and the filter removed nothing (docs/CROWDS.md).
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

// The valid (non-zero) raw depths of `region` (clipped to the image), on a regular grid of about
// `max_samples` pixels: robust statistics of a region do not need every pixel. `sum_u`, `sum_v` (optional)
// get the sums of the sampled pixels' coordinates added.
std::vector<uint16_t> sample_valid_depths(const cv::Mat& depth_image_raw, const cv::Rect& region,
                                          int max_samples, double* sum_u = nullptr, double* sum_v = nullptr);

enum class BoxDepthVerdict { kStandsOut, kFlat, kUnknown };

struct BoxDepthTest {
  BoxDepthVerdict verdict = BoxDepthVerdict::kUnknown;
  double torso_m = -1.0;    // median depth of the torso region (<= 0: none)
  double surface_m = -1.0;  // the deepest surface the planes predict there (<= 0: none)
};

// depth_image_raw: CV_16UC1, metres = value / depth_factor, 0 = no measurement.
BoxDepthTest box_depth_test(const cv::Mat& depth_image_raw, double depth_factor, const cv::Rect2f& box,
                            double margin_m, const std::vector<cv::Rect2f>& other_people = {});

// Whether a raw (before-NMS) box is flat given its own verdict (`own`) and the NMS boxes with theirs: it
// is flat when it is found flat itself or when the NMS box it overlaps most, the detection it
// duplicates, is (the raw neighbours of a false positive on a poster are the same false positive). A
// wider raw box of a false positive often spans other surfaces too and then stands out on its own: in
// the synthetic stereo false-positive room such boxes covered 60-90 % of the image after their NMS box
// was found flat, and tracking was lost (docs/CROWDS.md). Flat = kFlat.
bool flat_by_leader(const cv::Rect2f& box, BoxDepthVerdict own, const std::vector<PersonBox>& nms_boxes,
                    const std::vector<BoxDepthVerdict>& nms_verdicts);

}  // namespace crowdslam::people
