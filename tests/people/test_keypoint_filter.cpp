#include <gtest/gtest.h>

#include <cmath>

#include "crowdslam/people/feature_budget.h"
#include "crowdslam/people/keypoint_filter.h"
#include "crowdslam/util/error.h"

using namespace crowdslam;
using namespace crowdslam::people;

namespace {
PersonBox box(float x, float y, float w, float h) { return {cv::Rect2f(x, y, w, h), 0.9f}; }
cv::KeyPoint kp(float x, float y) { return cv::KeyPoint(cv::Point2f(x, y), 31.0f); }
}  // namespace

TEST(KeypointFilter, PaperModeDropsInsideGrownBoxesOnly) {
  const std::vector<cv::KeyPoint> kps{kp(50, 50), kp(104, 50), kp(106, 50), kp(10, 10), kp(150, 150)};
  KeypointFilterOptions options;  // margin 5
  const auto r = filter_keypoints(kps, {box(40, 40, 60, 60), box(140, 140, 20, 20)}, options);
  // Box 1 grown: x in [35, 105): 50 and 104 inside, 106 outside.
  EXPECT_EQ(r.keep, (std::vector<bool>{false, false, true, true, false}));
  EXPECT_EQ(r.removed, 3);
  // Which box removed each keypoint (tracking's static-box check counts them per box).
  EXPECT_EQ(r.box, (std::vector<int>{0, 0, -1, -1, 1}));
}

TEST(KeypointFilter, BoxIndicesCountTheCallersBoxesEvenWhenSomeAreIgnored) {
  const std::vector<cv::KeyPoint> kps{kp(50, 50), kp(150, 150)};
  KeypointFilterOptions options;
  const auto r = filter_keypoints(kps, {box(40, 40, 0, 20), box(40, 40, 20, 20), box(140, 140, 20, 20)}, options);
  EXPECT_EQ(r.box, (std::vector<int>{1, 2}));
}

TEST(KeypointFilter, DegenerateAndNanBoxesAreIgnored) {
  const std::vector<cv::KeyPoint> kps{kp(50, 50)};
  KeypointFilterOptions options;
  const auto r = filter_keypoints(kps,
                                  {box(40, 40, 0, 20), box(40, 40, -5, 20), box(std::nanf(""), 40, 20, 20),
                                   box(40, 40, 20, std::nanf(""))},
                                  options);
  EXPECT_TRUE(r.keep[0]);
}

TEST(KeypointFilter, DepthModeKeepsBackgroundBehindPerson) {
  // Depth image: person at 2 m in the box, background at 5 m elsewhere.
  cv::Mat depth(200, 200, CV_16UC1, cv::Scalar(5 * 5000));
  depth(cv::Rect(60, 40, 60, 140)).setTo(2 * 5000);
  const PersonBox person = box(50, 30, 80, 160);  // loose box around the person
  EXPECT_NEAR(estimate_person_depth(depth, 5000.0, person.box), 2.0, 1e-9);

  const std::vector<cv::KeyPoint> kps{kp(90, 100), kp(55, 100), kp(125, 35), kp(90, 150)};
  const std::vector<float> depth_m{2.0f, 5.0f, 5.0f, -1.0f};  // person, background, background, unknown
  KeypointFilterOptions options;
  options.mode = FilterMode::kDepth;
  const auto r = filter_keypoints(kps, {person}, options, depth_m, depth, 5000.0);
  EXPECT_EQ(r.keep, (std::vector<bool>{false, true, true, false}));
  // The same in paper mode drops all four.
  options.mode = FilterMode::kPaper;
  EXPECT_EQ(filter_keypoints(kps, {person}, options, depth_m).removed, 4);
}

TEST(KeypointFilter, AWideBoxOffThePersonsCentreKeepsTheBackgroundWithALowQuantile) {
  // A person at 1.5 m (x 40-69) at the left of a box twice their width (x 30-149, the body detector at
  // 160 x 160): the box's central region (x 60-119) shows them in 10 of its 60 columns, the wall at 4 m
  // in the rest.
  cv::Mat depth(200, 200, CV_16UC1, cv::Scalar(4 * 5000));
  depth(cv::Rect(40, 20, 30, 170)).setTo(static_cast<int>(1.5 * 5000));
  const PersonBox wide = box(30, 20, 120, 170);
  // The 30th percentile is the wall's depth: everything in the box would be filtered as the person.
  EXPECT_NEAR(estimate_person_depth(depth, 5000.0, wide.box, 0.3), 4.0, 1e-9);
  EXPECT_NEAR(estimate_person_depth(depth, 5000.0, wide.box, 0.1), 1.5, 1e-9);
  const std::vector<cv::KeyPoint> kps{kp(55, 100), kp(100, 100), kp(140, 60)};  // person, wall, wall
  const std::vector<float> depth_m{1.5f, 4.0f, 4.0f};
  KeypointFilterOptions options;
  options.mode = FilterMode::kDepth;
  EXPECT_EQ(filter_keypoints(kps, {wide}, options, depth_m, depth, 5000.0).keep,
            (std::vector<bool>{false, false, false}));
  options.person_depth_quantile = 0.1;
  EXPECT_EQ(filter_keypoints(kps, {wide}, options, depth_m, depth, 5000.0).keep,
            (std::vector<bool>{false, true, true}));
}

TEST(KeypointFilter, SilhouettesDropsBackgroundKeypointsOnThePersonsOutline) {
  // The scene above: a person at 2 m (x 60-119, y 40-179) before a background at 5 m.
  cv::Mat depth(200, 200, CV_16UC1, cv::Scalar(5 * 5000));
  depth(cv::Rect(60, 40, 60, 140)).setTo(2 * 5000);
  const PersonBox person = box(50, 30, 80, 160);
  // Background at their centres; the 5 x 5 neighbourhoods of the second (2 px left of the body) and
  // third (diagonally off its top-right corner) reach the person's outline, the last (6 px right) does not.
  const std::vector<cv::KeyPoint> kps{kp(90, 100), kp(58, 100), kp(121, 38), kp(126, 170)};
  const std::vector<float> depth_m{2.0f, 5.0f, 5.0f, 5.0f};
  KeypointFilterOptions options;
  options.mode = FilterMode::kDepth;
  EXPECT_TRUE(options.silhouettes);  // the default
  EXPECT_EQ(filter_keypoints(kps, {person}, options, depth_m, depth, 5000.0).keep,
            (std::vector<bool>{false, false, false, true}));
  options.silhouettes = false;
  EXPECT_EQ(filter_keypoints(kps, {person}, options, depth_m, depth, 5000.0).keep,
            (std::vector<bool>{false, true, true, true}));
  options.silhouettes = true;
  // Something well in front of the person (0.5 m: beyond the margin) beside the keypoint is not their outline.
  depth(cv::Rect(124, 160, 20, 20)).setTo(2500);
  EXPECT_TRUE(filter_keypoints(kps, {person}, options, depth_m, depth, 5000.0).keep[3]);
}

TEST(KeypointFilter, BackgroundCloseBehindThePersonIsKeptOnlyClearOfTheirOutline) {
  // A person at 2 m (x 60-119) before a wall 0.7 m behind them: beyond the margin (0.5 m), but within
  // two margins, so a keypoint there needs the middle of its ORB patch (8 px) clear of the person.
  cv::Mat depth(200, 200, CV_16UC1, cv::Scalar(static_cast<int>(2.7 * 5000)));
  depth(cv::Rect(60, 40, 60, 140)).setTo(2 * 5000);
  const PersonBox person = box(50, 30, 100, 160);
  KeypointFilterOptions options;
  options.mode = FilterMode::kDepth;
  EXPECT_DOUBLE_EQ(options.depth_margin_m, 0.5);  // the default
  // 6 px right of the body: its patch sees the person's edge; 12 px right: clear of it.
  const std::vector<cv::KeyPoint> kps{kp(125, 100), kp(131, 100)};
  EXPECT_EQ(filter_keypoints(kps, {person}, options, {2.7f, 2.7f}, depth, 5000.0).keep,
            (std::vector<bool>{false, true}));
  // A wall 1.5 m behind (beyond two margins): only the 5 x 5 neighbourhood has to be clear.
  depth.setTo(static_cast<int>(3.5 * 5000));
  depth(cv::Rect(60, 40, 60, 140)).setTo(2 * 5000);
  EXPECT_EQ(filter_keypoints(kps, {person}, options, {3.5f, 3.5f}, depth, 5000.0).keep,
            (std::vector<bool>{true, true}));
  // Within the margin (2.3 m): the person's, dropped wherever it is in the box.
  EXPECT_EQ(filter_keypoints({kp(140, 100)}, {person}, options, {2.3f}, depth, 5000.0).keep,
            (std::vector<bool>{false}));
}

TEST(KeypointFilter, BadModeAndMarginAreInputErrors) {
  EXPECT_THROW(parse_filter_mode("mask", "PeopleFilter.mode"), InputError);
  KeypointFilterOptions options;
  options.margin_px = -1;
  EXPECT_THROW(options.check(), InputError);
}

TEST(FeatureBudget, PaperScheduleAtEachThreshold) {
  FeatureBudgetOptions options;  // 1000 at 640x480
  EXPECT_EQ(feature_budget(0.0, options), 1000);
  EXPECT_EQ(feature_budget(0.01, options), 1300);
  EXPECT_EQ(feature_budget(0.29, options), 1300);
  EXPECT_EQ(feature_budget(0.3, options), 1500);
  EXPECT_EQ(feature_budget(0.6, options), 1700);
  EXPECT_EQ(feature_budget(0.9, options), 1900);
  EXPECT_EQ(feature_budget(0.95, options), 2200);
  EXPECT_EQ(feature_budget(1.7, options), 2200);
  options.enabled = false;
  EXPECT_EQ(feature_budget(0.5, options), 1000);
  // Base scaled by image area relative to 640x480.
  options.enabled = true;
  options.image_width = 1280;
  options.image_height = 960;
  EXPECT_EQ(feature_budget(0.0, options), 4000);
}

TEST(FeatureBudget, SumVersusUnionArea) {
  // Two 100x100 boxes overlapping by 50x100, in a 400x100 image; a third partly outside the image.
  const std::vector<PersonBox> boxes{box(0, 0, 100, 100), box(50, 0, 100, 100), box(350, 50, 100, 100)};
  // Sum: 10000 + 10000 + 50*50 (clipped) = 22500 of 40000.
  EXPECT_NEAR(covered_fraction(boxes, 400, 100, AreaMode::kSum), 22500.0 / 40000.0, 1e-12);
  // Union: 150*100 + 2500 = 17500.
  EXPECT_NEAR(covered_fraction(boxes, 400, 100, AreaMode::kUnion), 17500.0 / 40000.0, 1e-12);
  EXPECT_EQ(covered_fraction({}, 400, 100, AreaMode::kUnion), 0.0);
}

TEST(FeatureBudget, InconsistentScheduleIsRejected) {
  FeatureBudgetOptions options;
  options.factors.pop_back();
  EXPECT_THROW(options.check(), InputError);
  options = FeatureBudgetOptions{};
  options.thresholds = {0.0, 0.5, 0.3, 0.9, 0.95};
  EXPECT_THROW(options.check(), InputError);
}
