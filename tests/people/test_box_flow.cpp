// Box propagation by optical flow: a textured person patch moved by a known shift (and scale) between
// two synthetic frames must move its box by that shift; a box on a flat background stays put.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "crowdslam/people/box_flow.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

// Smooth random texture (blurred noise): LK needs gradients, corners need texture.
cv::Mat textured(cv::Size size, int seed, double sigma = 2.0) {
  cv::Mat noise(size, CV_8UC1);
  cv::RNG rng(static_cast<uint64_t>(seed));
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::Mat smooth;
  cv::GaussianBlur(noise, smooth, cv::Size(0, 0), sigma);
  cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
  return smooth;
}

// A flat grey frame with a textured "person" patch at `rect`.
cv::Mat frame_with_patch(const cv::Mat& patch, const cv::Rect& rect) {
  cv::Mat frame(480, 640, CV_8UC1, cv::Scalar(120));
  cv::Mat resized;
  cv::resize(patch, resized, rect.size(), 0, 0, cv::INTER_LINEAR);
  resized.copyTo(frame(rect));
  return frame;
}

TEST(BoxFlow, MovesBoxByKnownShift) {
  const cv::Mat patch = textured(cv::Size(80, 160), 7);
  const cv::Rect at0(200, 150, 80, 160);
  const cv::Rect at1(207, 146, 80, 160);  // shifted by (+7, -4)
  const cv::Mat f0 = frame_with_patch(patch, at0);
  const cv::Mat f1 = frame_with_patch(patch, at1);
  std::vector<FlowBox> boxes{FlowBox{PersonBox{cv::Rect2f(200, 150, 80, 160), 0.9f}, {}, 3}};
  BoxFlowOptions options;
  seed_points(f0, boxes, options);
  ASSERT_GE(boxes[0].points.size(), 10u);
  const FlowStats stats = move_boxes(f0, f1, boxes, options);
  EXPECT_EQ(stats.boxes_moved, 1u);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_NEAR(boxes[0].box.box.x, 207.0, 0.5);
  EXPECT_NEAR(boxes[0].box.box.y, 146.0, 0.5);
  EXPECT_NEAR(boxes[0].box.box.width, 80.0, 1.0);
  EXPECT_NEAR(boxes[0].box.box.height, 160.0, 1.5);
  EXPECT_EQ(boxes[0].track_id, 3);            // identity and confidence travel with the box
  EXPECT_FLOAT_EQ(boxes[0].box.confidence, 0.9f);
  for (const auto& p : boxes[0].points) EXPECT_TRUE(boxes[0].box.box.contains(p));
}

TEST(BoxFlow, ScalesBoxWithApproachingPerson) {
  const cv::Mat patch = textured(cv::Size(100, 200), 11);
  const cv::Mat f0 = frame_with_patch(patch, cv::Rect(270, 140, 100, 200));
  // 10 % larger about the same centre (320, 240).
  const cv::Mat f1 = frame_with_patch(patch, cv::Rect(265, 130, 110, 220));
  std::vector<FlowBox> boxes{FlowBox{PersonBox{cv::Rect2f(270, 140, 100, 200), 0.5f}, {}, -1}};
  BoxFlowOptions options;
  seed_points(f0, boxes, options);
  move_boxes(f0, f1, boxes, options);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_NEAR(boxes[0].box.box.width, 110.0, 3.0);
  EXPECT_NEAR(boxes[0].box.box.height, 220.0, 5.0);
  EXPECT_NEAR(boxes[0].box.box.x + boxes[0].box.box.width / 2, 320.0, 1.0);
  EXPECT_NEAR(boxes[0].box.box.y + boxes[0].box.box.height / 2, 240.0, 1.5);
}

TEST(BoxFlow, BoxOnFlatBackgroundStaysInPlace) {
  const cv::Mat flat(480, 640, CV_8UC1, cv::Scalar(90));
  std::vector<FlowBox> boxes{FlowBox{PersonBox{cv::Rect2f(50, 60, 70, 140), 0.4f}, {}, -1}};
  BoxFlowOptions options;
  seed_points(flat, boxes, options);
  EXPECT_TRUE(boxes[0].points.empty());
  const FlowStats stats = move_boxes(flat, flat, boxes, options);
  EXPECT_EQ(stats.boxes_kept, 1u);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_EQ(boxes[0].box.box, cv::Rect2f(50, 60, 70, 140));
}

TEST(BoxFlow, BoxLeavingTheImageIsClipped) {
  // The whole frame moves left by 40 px: a box 60 px wide at x = 20 half leaves the image; its corners
  // that stay visible move it, and it is clipped at the edge. The other box moves with them.
  cv::Mat f0 = textured(cv::Size(640, 480), 9, 5.0);  // coarse texture: a 40 px move is in LK's range
  cv::Mat f1(f0.size(), f0.type(), cv::Scalar(0));
  f0(cv::Rect(40, 0, 600, 480)).copyTo(f1(cv::Rect(0, 0, 600, 480)));
  std::vector<FlowBox> boxes{FlowBox{PersonBox{cv::Rect2f(20, 100, 60, 120), 0.5f}, {}, 1},
                             FlowBox{PersonBox{cv::Rect2f(300, 100, 60, 120), 0.5f}, {}, 2}};
  BoxFlowOptions options;
  options.window = 31;
  seed_points(f0, boxes, options);
  move_boxes(f0, f1, boxes, options);
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_NEAR(boxes[0].box.box.x, 0.0, 1e-6);
  EXPECT_NEAR(boxes[0].box.box.width, 40.0, 1.0);
  EXPECT_NEAR(boxes[1].box.box.x, 260.0, 0.5);
  EXPECT_NEAR(boxes[1].box.box.width, 60.0, 1.0);
}

TEST(BoxFlow, OptionsAreChecked) {
  BoxFlowOptions options;
  options.min_points = 0;
  EXPECT_THROW(options.check(), InputError);
  options = BoxFlowOptions{};
  options.forward_backward_px = 0;
  EXPECT_THROW(options.check(), InputError);
}

TEST(BoxFlow, ReportsEachBoxsMotionWithPrebuiltPyramids) {
  const cv::Mat patch = textured(cv::Size(80, 160), 7);
  const cv::Mat f0 = frame_with_patch(patch, cv::Rect(200, 150, 80, 160));
  const cv::Mat f1 = frame_with_patch(patch, cv::Rect(207, 146, 80, 160));  // shifted by (+7, -4)
  BoxFlowOptions options;
  // The person's box, and a box on the flat background that cannot be tracked.
  std::vector<FlowBox> boxes{FlowBox{PersonBox{cv::Rect2f(200, 150, 80, 160), 0.9f}, {}, -1},
                             FlowBox{PersonBox{cv::Rect2f(450, 50, 80, 100), 0.4f}, {}, -1}};
  seed_points(f0, boxes, options);
  std::vector<BoxMotion> motions;
  const FlowStats stats =
      move_boxes(make_flow_image(f0, options), make_flow_image(f1, options), boxes, options, &motions);
  EXPECT_EQ(stats.boxes_moved, 1u);
  EXPECT_EQ(stats.boxes_kept, 1u);
  ASSERT_EQ(motions.size(), 2u);
  EXPECT_TRUE(motions[0].moved);
  EXPECT_NEAR(motions[0].dx, 7.0, 0.3);
  EXPECT_NEAR(motions[0].dy, -4.0, 0.3);
  EXPECT_NEAR(motions[0].scale, 1.0, 0.02);
  EXPECT_FALSE(motions[1].moved);
  EXPECT_FALSE(motions[1].left_image);
}

TEST(BoxFlow, AFollowerTakesItsLeadersMotionAboutTheLeadersCentre) {
  const cv::Point2f leader_centre(100, 100);
  const BoxMotion motion{true, false, 5.0, -3.0, 1.1};
  // Centre (100, 120): 20 px below the leader's centre, so 22 px below it after the 1.1 scale.
  const cv::Rect2f moved = follow_motion(cv::Rect2f(80, 90, 40, 60), leader_centre, motion, 640, 480);
  EXPECT_NEAR(moved.x + 0.5 * moved.width, 105.0, 1e-4);
  EXPECT_NEAR(moved.y + 0.5 * moved.height, 119.0, 1e-4);
  EXPECT_NEAR(moved.width, 44.0, 1e-4);
  EXPECT_NEAR(moved.height, 66.0, 1e-4);
  // A leader left in place leaves its followers in place; one that left the image takes them along.
  const cv::Rect2f kept = follow_motion(cv::Rect2f(80, 90, 40, 60), leader_centre, BoxMotion{}, 640, 480);
  EXPECT_EQ(kept, cv::Rect2f(80, 90, 40, 60));
  const cv::Rect2f gone =
      follow_motion(cv::Rect2f(80, 90, 40, 60), leader_centre, BoxMotion{false, true, 0, 0, 1}, 640, 480);
  EXPECT_FALSE(gone.width > 0 && gone.height > 0);
  // Clipped to the image.
  const cv::Rect2f clipped =
      follow_motion(cv::Rect2f(600, 90, 40, 60), cv::Point2f(620, 120), BoxMotion{true, false, 30, 0, 1}, 640, 480);
  EXPECT_NEAR(clipped.x + clipped.width, 640.0, 1e-4);
}

}  // namespace
}  // namespace crowdslam::people
