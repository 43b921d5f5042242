// The person's surface grown from their box over a depth image (people/person_segment.h), and the depth
// filter keeping the background close behind a person but off their surface (keypoint_filter.h).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "crowdslam/people/keypoint_filter.h"
#include "crowdslam/people/person_segment.h"

using crowdslam::people::filter_keypoints;
using crowdslam::people::FilterMode;
using crowdslam::people::KeypointFilterOptions;
using crowdslam::people::PersonBox;
using crowdslam::people::PersonSegment;

namespace {
constexpr double kFactor = 5000.0;

double person_depth_at(int x) {
  // A body 100 px wide whose front is 2.0 m away; its sides curve back to 2.25 m.
  const double dx = (x - 250) / 50.0;
  return 2.0 + 0.25 * dx * dx;
}

// A wall 3 m away; a person at x 200-299, y 100-399; right beside them, x 300-359 over their height, a
// cupboard 2.45 m away (a step of 0.2 m from the person's side, 0.45 m from their front); under the
// person a floor rising towards the camera from their feet (2.0 m at y 400 to 1.6 m at the bottom).
cv::Mat scene() {
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(static_cast<uint16_t>(3.0 * kFactor)));
  auto set = [&](int x, int y, double m) {
    depth.at<uint16_t>(y, x) = static_cast<uint16_t>(std::lround(m * kFactor));
  };
  for (int y = 100; y < 400; ++y) {
    for (int x = 200; x < 300; ++x) set(x, y, person_depth_at(x));
    for (int x = 300; x < 360; ++x) set(x, y, 2.45);
  }
  for (int y = 400; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) set(x, y, 2.0 - 0.4 * (y - 400) / 79.0);
  }
  return depth;
}
}  // namespace

TEST(PersonSegment, CoversThePersonAndTheFloorUnderThemButNotWhatStandsBehindThem) {
  const cv::Mat depth = scene();
  const cv::Rect2f box(180, 90, 200, 390);
  const PersonSegment segment(depth, kFactor, box, 2.0, 0.5);
  ASSERT_GT(segment.cells(), 0);
  EXPECT_TRUE(segment.near({250, 250}, 0));   // the front of the person
  EXPECT_TRUE(segment.near({296, 250}, 0));   // their side, 0.22 m behind their front
  EXPECT_TRUE(segment.near({204, 150}, 0));   // the other side
  EXPECT_TRUE(segment.near({250, 460}, 0));   // the floor they stand on
  EXPECT_FALSE(segment.near({330, 250}, 0));  // the cupboard beside them, 0.45 m behind their front
  EXPECT_FALSE(segment.near({330, 250}, 8));
  EXPECT_TRUE(segment.near({305, 250}, 8));  // within 8 px of their side: their outline
  EXPECT_FALSE(segment.near({190, 95}, 0));  // the wall, 1 m behind them: outside the depth window
}

TEST(PersonSegment, IsEmptyWithoutDepthOrPerson) {
  const cv::Mat none(480, 640, CV_16UC1, cv::Scalar(0));
  EXPECT_EQ(PersonSegment(none, kFactor, cv::Rect2f(180, 90, 200, 390), 2.0, 0.5).cells(), 0);
  EXPECT_EQ(PersonSegment(scene(), kFactor, cv::Rect2f(180, 90, 200, 390), -1.0, 0.5).cells(), 0);
  EXPECT_EQ(PersonSegment(cv::Mat(), kFactor, cv::Rect2f(180, 90, 200, 390), 2.0, 0.5).cells(), 0);
  EXPECT_FALSE(PersonSegment(none, kFactor, cv::Rect2f(180, 90, 200, 390), 2.0, 0.5).near({250, 250}, 8));
}

TEST(KeypointFilterSegments, KeepsTheBackgroundCloseBehindAPersonOffTheirSurface) {
  const cv::Mat depth = scene();
  PersonBox box;
  box.box = cv::Rect2f(180, 90, 200, 390);
  box.confidence = 0.9f;
  const std::vector<cv::KeyPoint> keys = {
      cv::KeyPoint(250, 250, 31),  // the person's front, 2.0 m
      cv::KeyPoint(296, 250, 31),  // the person's side, 2.22 m: within the band, on the person
      cv::KeyPoint(335, 250, 31),  // the cupboard, 2.45 m: within the margin, off the person
      cv::KeyPoint(250, 470, 31),  // the floor at their feet, 1.65 m
  };
  std::vector<float> depth_m;
  for (const auto& k : keys) {
    depth_m.push_back(static_cast<float>(depth.at<uint16_t>(cvRound(k.pt.y), cvRound(k.pt.x)) / kFactor));
  }
  KeypointFilterOptions options;
  options.mode = FilterMode::kDepth;
  options.person_depth_quantile = 0.1;
  const auto without = filter_keypoints(keys, {box}, options, depth_m, depth, kFactor);
  ASSERT_EQ(without.person_depth_m.size(), 1u);
  EXPECT_NEAR(without.person_depth_m[0], 2.0, 0.02);
  EXPECT_EQ(without.keep, (std::vector<bool>{false, false, false, false}));  // all within 0.5 m of 2.0

  options.segment_from_m = 0.15;
  const auto with = filter_keypoints(keys, {box}, options, depth_m, depth, kFactor);
  EXPECT_EQ(with.keep, (std::vector<bool>{false, false, true, false}));  // only the cupboard comes back
  EXPECT_EQ(with.removed, 3);
}
