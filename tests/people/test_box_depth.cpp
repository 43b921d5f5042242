// The depth test that tells a person box from a box on a flat surface (people/box_depth.h), on depth
// images rendered in closed form: planes (1/z affine in the pixel) with or without a slab in front.
#include <gtest/gtest.h>

#include <cmath>

#include "crowdslam/people/box_depth.h"

using namespace crowdslam::people;

namespace {
constexpr double kFactor = 5000.0;  // TUM/Bonn depth units per metre
constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr double kF = 525.0;
constexpr double kCx = 319.5;
constexpr double kCy = 239.5;

// Depth of the plane n . X = d seen through pixel (u, v) of a pinhole camera: z = d / (n . ray).
double plane_depth(const double n[3], double d, double u, double v) {
  const double ray = n[0] * (u - kCx) / kF + n[1] * (v - kCy) / kF + n[2];
  return d / ray;
}

cv::Mat plane_image(const double n[3], double d) {
  cv::Mat depth(kHeight, kWidth, CV_16UC1);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      depth.at<uint16_t>(v, u) = static_cast<uint16_t>(std::lround(plane_depth(n, d, u, v) * kFactor));
    }
  }
  return depth;
}

// A slab `closer_m` in front of the plane over the pixel rectangle `slab` (a person's body).
void add_slab(cv::Mat& depth, const cv::Rect& slab, double closer_m) {
  for (int v = slab.y; v < slab.y + slab.height; ++v) {
    for (int u = slab.x; u < slab.x + slab.width; ++u) {
      auto& z = depth.at<uint16_t>(v, u);
      z = static_cast<uint16_t>(std::lround(z - closer_m * kFactor));
    }
  }
}

const double kFrontal[3] = {0.0, 0.0, 1.0};
// A wall turned 50 degrees about the vertical axis (at 1.5 m from the camera centre): depth falls from
// 8.5 m to 1.35 m across the image.
const double kOblique[3] = {std::sin(50.0 * M_PI / 180.0), 0.0, std::cos(50.0 * M_PI / 180.0)};
}  // namespace

TEST(BoxDepth, ABoxOnAFrontalWallIsFlat) {
  const cv::Mat depth = plane_image(kFrontal, 3.0);
  const auto test = box_depth_test(depth, kFactor, cv::Rect2f(200, 100, 150, 300), 0.2);
  EXPECT_EQ(test.verdict, BoxDepthVerdict::kFlat);
  EXPECT_NEAR(test.torso_m, 3.0, 1e-3);
  EXPECT_NEAR(test.surface_m, 3.0, 1e-3);
}

TEST(BoxDepth, TheSurroundingPlanePredictsAnObliqueWallsDepthExactly) {
  const cv::Mat depth = plane_image(kOblique, 1.5);
  const cv::Rect2f box(300, 60, 200, 380);
  const auto test = box_depth_test(depth, kFactor, box, 0.2);
  EXPECT_EQ(test.verdict, BoxDepthVerdict::kFlat);
  // The torso region's median is the plane's depth near the region's centre (the region spans depths
  // that differ by about 0.3 m, so its median pixel is within a few centimetres of the centre's).
  const double centre_u = box.x + 0.5 * box.width;
  const double centre_v = box.y + 0.375 * box.height;
  const double expected = plane_depth(kOblique, 1.5, centre_u, centre_v);
  EXPECT_NEAR(test.surface_m, expected, 0.01 * expected);
  EXPECT_NEAR(test.torso_m, expected, 0.02 * expected);
}

TEST(BoxDepth, APersonInFrontOfTheWallStandsOut) {
  cv::Mat depth = plane_image(kOblique, 1.5);
  const cv::Rect2f box(300, 60, 160, 400);
  // The body fills the box's middle 60 % of its width and its full height, 0.4 m in front of the wall.
  add_slab(depth, cv::Rect(332, 60, 96, 400), 0.4);
  const auto test = box_depth_test(depth, kFactor, box, 0.2);
  EXPECT_EQ(test.verdict, BoxDepthVerdict::kStandsOut);
  EXPECT_NEAR(test.surface_m - test.torso_m, 0.4, 0.03);
  // The same person with a margin larger than the gap: flat.
  EXPECT_EQ(box_depth_test(depth, kFactor, box, 0.5).verdict, BoxDepthVerdict::kFlat);
}

TEST(BoxDepth, ABoxFillingTheImageWidthIsJudgedOnStripsInsideItsEdges) {
  // Touches the left, right and top edges: no surroundings on two sides, so the strips just inside the
  // box's left and right edges (15 % of its width each) stand in for them.
  cv::Mat wall = plane_image(kOblique, 1.5);
  const cv::Rect2f full_width(0, 0, 640, 400);
  const auto on_wall = box_depth_test(wall, kFactor, full_width, 0.2);
  EXPECT_EQ(on_wall.verdict, BoxDepthVerdict::kFlat);
  EXPECT_NEAR(on_wall.surface_m, on_wall.torso_m, 0.05 * on_wall.torso_m);
  // A person close to the camera, the body over the middle 60 % of the width, 0.5 m in front of the wall.
  cv::Mat person = wall.clone();
  add_slab(person, cv::Rect(128, 0, 384, 400), 0.5);
  const auto close_person = box_depth_test(person, kFactor, full_width, 0.2);
  EXPECT_EQ(close_person.verdict, BoxDepthVerdict::kStandsOut);
  EXPECT_GT(close_person.surface_m - close_person.torso_m, 0.4);
  // A body that fills the whole box leaves nothing to compare with but itself: flat (the cost: such a
  // person is not filtered, and left to the geometric check).
  cv::Mat filled = wall.clone();
  add_slab(filled, cv::Rect(0, 0, 640, 400), 0.5);
  EXPECT_EQ(box_depth_test(filled, kFactor, full_width, 0.2).verdict, BoxDepthVerdict::kFlat);
  // Only the right side and the top are seen: two sides outside, decided as before.
  EXPECT_EQ(box_depth_test(plane_image(kFrontal, 3.0), kFactor, cv::Rect2f(0, 50, 400, 400), 0.2).verdict,
            BoxDepthVerdict::kFlat);
  // Without depth in the strips either: undecided.
  cv::Mat holes = wall.clone();
  holes(cv::Rect(0, 0, 96, 480)).setTo(0);
  EXPECT_EQ(box_depth_test(holes, kFactor, full_width, 0.2).verdict, BoxDepthVerdict::kUnknown);
}

TEST(BoxDepth, ANarrowBoxAtTheLeftEdgeIsJudgedOnStripsWideEnoughToHoldDepth) {
  // Stereo near the left edge: no ORB keypoints within ~20 px and no right-image match closer than the
  // disparity, so the first 40 columns hold no depth. A box 194 px wide from the image's (or nearly the
  // image's) left edge, full height: no surroundings left, above or below; 15 % of its width (29 px)
  // would be a strip of holes, the strip is 64 px instead.
  cv::Mat wall = plane_image(kOblique, 1.5);
  wall(cv::Rect(0, 0, 40, kHeight)).setTo(0);
  for (const float x : {0.0F, 12.0F}) {
    const cv::Rect2f box(x, 0, 194, 480);
    const auto on_wall = box_depth_test(wall, kFactor, box, 0.2);
    EXPECT_EQ(on_wall.verdict, BoxDepthVerdict::kFlat) << "box at x " << x;
    // Here the oblique wall is 4-8 m deep and its depth doubles across the box: medians of depth over
    // the patches are not the depth at their centres, so the plane is within 10 %, not exact.
    EXPECT_NEAR(on_wall.surface_m, on_wall.torso_m, 0.1 * on_wall.torso_m);
    // A person in the box's middle, 0.5 m in front of the wall: stands out.
    cv::Mat person = wall.clone();
    add_slab(person, cv::Rect(static_cast<int>(x) + 70, 0, 60, 480), 0.5);
    EXPECT_EQ(box_depth_test(person, kFactor, box, 0.2).verdict, BoxDepthVerdict::kStandsOut)
        << "box at x " << x;
  }
  // A box well inside the image with holes around it is still undecided.
  cv::Mat holes = plane_image(kOblique, 1.5);
  holes(cv::Rect(100, 0, 60, kHeight)).setTo(0);
  holes(cv::Rect(0, 0, kWidth, 40)).setTo(0);
  EXPECT_EQ(box_depth_test(holes, kFactor, cv::Rect2f(160, 0, 200, 480), 0.2).verdict,
            BoxDepthVerdict::kUnknown);
}

TEST(BoxDepth, APersonCutByTheImagesEdgeStandsOutOfWhatIsBesideThem) {
  // A person 0.7 m from the camera, cut by the image's left (or right) edge, fills their box from the
  // top of the image to the bottom: no side outside the box but one. The strips inside both edges of the
  // box show the person; the side outside shows the wall 4 m away. Judged on the inner strips alone the
  // box was flat on the person (their keypoints then reached the map: docs/CROWDS.md).
  for (const bool left : {true, false}) {
    SCOPED_TRACE(left ? "left edge" : "right edge");
    const cv::Rect body = left ? cv::Rect(0, 0, 207, kHeight) : cv::Rect(kWidth - 207, 0, 207, kHeight);
    const cv::Rect2f box(static_cast<float>(body.x), 0, 207, kHeight);
    cv::Mat person = plane_image(kFrontal, 4.0);
    add_slab(person, body, 3.3);
    const auto close = box_depth_test(person, kFactor, box, 0.2);
    EXPECT_EQ(close.verdict, BoxDepthVerdict::kStandsOut);
    EXPECT_NEAR(close.torso_m, 0.7, 1e-3);
    EXPECT_GT(close.surface_m - close.torso_m, 0.2);
    // The same box on a wall, frontal or oblique either way: the side outside and the strip at the
    // image's edge lie on one plane with the box's middle.
    const double mirrored[3] = {-kOblique[0], kOblique[1], kOblique[2]};
    for (const double* normal : {kFrontal, kOblique, mirrored}) {
      const auto wall = box_depth_test(plane_image(normal, 1.5), kFactor, box, 0.2);
      EXPECT_EQ(wall.verdict, BoxDepthVerdict::kFlat) << "normal x " << normal[0];
      EXPECT_NEAR(wall.surface_m, wall.torso_m, 0.1 * wall.torso_m) << "normal x " << normal[0];
    }
  }
}

TEST(BoxDepth, NoDepthIsUndecided) {
  const cv::Mat empty;
  EXPECT_EQ(box_depth_test(empty, kFactor, cv::Rect2f(200, 100, 150, 300), 0.2).verdict,
            BoxDepthVerdict::kUnknown);
  const cv::Mat zeros = cv::Mat::zeros(kHeight, kWidth, CV_16UC1);
  const auto test = box_depth_test(zeros, kFactor, cv::Rect2f(200, 100, 150, 300), 0.2);
  EXPECT_EQ(test.verdict, BoxDepthVerdict::kUnknown);
  EXPECT_LE(test.torso_m, 0.0);
  // Depth on the torso but none around it (holes in the depth image): undecided.
  cv::Mat torso_only = cv::Mat::zeros(kHeight, kWidth, CV_16UC1);
  torso_only(cv::Rect(200, 100, 150, 300)).setTo(2 * kFactor);
  EXPECT_EQ(box_depth_test(torso_only, kFactor, cv::Rect2f(200, 100, 150, 300), 0.2).verdict,
            BoxDepthVerdict::kUnknown);
  // A float image is not a raw depth image.
  cv::Mat wrong_type(kHeight, kWidth, CV_32FC1, cv::Scalar(2.0));
  EXPECT_EQ(box_depth_test(wrong_type, kFactor, cv::Rect2f(200, 100, 150, 300), 0.2).verdict,
            BoxDepthVerdict::kUnknown);
}

TEST(BoxDepth, ARawBoxIsFlatWhenItOrTheNmsBoxItDuplicatesIsFlat) {
  const std::vector<PersonBox> nms = {{{100, 50, 200, 400}, 0.9F}, {{400, 50, 150, 400}, 0.8F}};
  const std::vector<BoxDepthVerdict> verdicts = {BoxDepthVerdict::kFlat, BoxDepthVerdict::kStandsOut};
  // Raw neighbours too small to test: the one over the poster (IoU 0.6 with the flat box) is flat, the
  // one over the person is not.
  EXPECT_TRUE(flat_by_leader({120, 60, 150, 320}, BoxDepthVerdict::kUnknown, nms, verdicts));
  EXPECT_FALSE(flat_by_leader({410, 60, 130, 380}, BoxDepthVerdict::kUnknown, nms, verdicts));
  // Overlapping both, it follows the one it overlaps most (IoU 0.37 with the person's box, 0.05 with the
  // poster).
  EXPECT_FALSE(flat_by_leader({280, 50, 220, 400}, BoxDepthVerdict::kUnknown, nms, verdicts));
  // Found flat on its own, it is flat whatever its leader; standing out on its own, it still follows a
  // flat leader (a wider box of the same false positive reaching other surfaces), not a standing one.
  EXPECT_TRUE(flat_by_leader({410, 60, 130, 380}, BoxDepthVerdict::kFlat, nms, verdicts));
  EXPECT_TRUE(flat_by_leader({120, 60, 150, 320}, BoxDepthVerdict::kStandsOut, nms, verdicts));
  EXPECT_FALSE(flat_by_leader({410, 60, 130, 380}, BoxDepthVerdict::kStandsOut, nms, verdicts));
  // No NMS box it overlaps, or none at all: not flat.
  EXPECT_FALSE(flat_by_leader({600, 0, 30, 30}, BoxDepthVerdict::kUnknown, nms, verdicts));
  EXPECT_FALSE(flat_by_leader({120, 60, 150, 320}, BoxDepthVerdict::kUnknown, {}, {}));
}

TEST(BoxDepth, APersonAmongPeopleIsNotJudgedFlatOnTheNeighboursBesideThem) {
  // A row of three people 0.6 m from the camera hides a wall 3 m away from edge to edge: the patches
  // beside each box show the neighbours, at the person's own depth.
  cv::Mat depth = plane_image(kFrontal, 3.0);
  const cv::Rect2f boxes[3] = {{0, 0, 220, 480}, {210, 0, 220, 480}, {420, 0, 220, 480}};
  for (const auto& b : boxes) add_slab(depth, cv::Rect(b), 2.4);
  const std::vector<cv::Rect2f> people(std::begin(boxes), std::end(boxes));
  // Judged on the neighbours (the test's behaviour without the other boxes): flat, so not filtered.
  EXPECT_EQ(box_depth_test(depth, kFactor, boxes[1], 0.2).verdict, BoxDepthVerdict::kFlat);
  // With the other people's boxes, no patch shows the surface behind the middle person: undecided, kept.
  for (const auto& b : boxes) {
    EXPECT_NE(box_depth_test(depth, kFactor, b, 0.2, people).verdict, BoxDepthVerdict::kFlat);
  }
  // A box's own duplicate (IoU >= 0.5) is not another person: a poster is still flat with its raw twin.
  const cv::Mat wall = plane_image(kFrontal, 3.0);
  const cv::Rect2f poster(250, 100, 140, 250);
  const std::vector<cv::Rect2f> twin = {cv::Rect2f(255, 105, 140, 250)};
  EXPECT_EQ(box_depth_test(wall, kFactor, poster, 0.2, twin).verdict, BoxDepthVerdict::kFlat);
  // A person beside the middle one, 1 m in front of the wall, with the wall visible beyond them both:
  // judged on the wall, they stand out.
  cv::Mat pair = plane_image(kFrontal, 3.0);
  const cv::Rect2f left(200, 100, 100, 300), right(300, 100, 100, 300);
  add_slab(pair, cv::Rect(left), 1.0);
  add_slab(pair, cv::Rect(right), 1.0);
  const std::vector<cv::Rect2f> both = {left, right};
  EXPECT_EQ(box_depth_test(pair, kFactor, left, 0.2, both).verdict, BoxDepthVerdict::kStandsOut);
  EXPECT_EQ(box_depth_test(pair, kFactor, right, 0.2, both).verdict, BoxDepthVerdict::kStandsOut);
}
