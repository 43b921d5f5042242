// DetectorOptions::check, box helpers, NMS.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "crowdslam/people/detector.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

std::string check_message(const DetectorOptions& o) {
  try {
    o.check();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DetectorOptions, DefaultsArePaperValues) {
  const DetectorOptions o;
  EXPECT_NO_THROW(o.check());
  EXPECT_EQ(o.input_size, 160);
  EXPECT_DOUBLE_EQ(o.confidence, 0.2);
  EXPECT_DOUBLE_EQ(o.nms, 0.1);
}

TEST(DetectorOptions, BadValuesNameTheKeyAndValue) {
  DetectorOptions o;
  o.input_size = 100;
  EXPECT_NE(check_message(o).find("input_size"), std::string::npos);
  EXPECT_NE(check_message(o).find("100"), std::string::npos);
  o.input_size = 0;
  EXPECT_NE(check_message(o).find("input_size"), std::string::npos);
  o = {};
  o.confidence = 1.5;
  EXPECT_NE(check_message(o).find("confidence"), std::string::npos);
  o.confidence = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(check_message(o).find("confidence"), std::string::npos);
  o = {};
  o.nms = -0.1;
  EXPECT_NE(check_message(o).find("nms"), std::string::npos);
  o = {};
  o.person_class = -1;
  EXPECT_NE(check_message(o).find("person_class"), std::string::npos);
  o = {};
  o.input_size = 32;
  o.confidence = 0;
  o.nms = 1;
  EXPECT_EQ(check_message(o), "");
}

TEST(ClipBox, ClipsToImageAndEmptiesOutsideOrNaN) {
  const cv::Rect2f c = clip_box({-10, -5, 30, 20}, 100, 50);
  EXPECT_FLOAT_EQ(c.x, 0);
  EXPECT_FLOAT_EQ(c.y, 0);
  EXPECT_FLOAT_EQ(c.width, 20);
  EXPECT_FLOAT_EQ(c.height, 15);
  const cv::Rect2f r = clip_box({90, 40, 30, 20}, 100, 50);
  EXPECT_FLOAT_EQ(r.width, 10);
  EXPECT_FLOAT_EQ(r.height, 10);
  EXPECT_LE(clip_box({120, 10, 5, 5}, 100, 50).width, 0);
  EXPECT_LE(clip_box({10, 10, -5, 5}, 100, 50).width, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const cv::Rect2f n = clip_box({nan, 10, 5, 5}, 100, 50);
  EXPECT_FALSE(n.width > 0 && n.height > 0);
}

TEST(BoxIou, ClosedForm) {
  // Same height, x-overlap 5 of width 10: inter 50, union 150.
  EXPECT_NEAR(box_iou({0, 0, 10, 10}, {5, 0, 10, 10}), 50.0 / 150.0, 1e-12);
  EXPECT_NEAR(box_iou({0, 0, 10, 10}, {0, 0, 10, 10}), 1.0, 1e-12);
  EXPECT_EQ(box_iou({0, 0, 10, 10}, {10, 0, 10, 10}), 0.0);
  EXPECT_EQ(box_iou({0, 0, 0, 10}, {0, 0, 10, 10}), 0.0);
  // Box inside a box: 4 / 100.
  EXPECT_NEAR(box_iou({0, 0, 10, 10}, {2, 2, 2, 2}), 0.04, 1e-12);
}

TEST(SuppressNonMaxima, KeepsBestOfOverlappingAndDisjointBoxes) {
  const std::vector<PersonBox> boxes = {
      {{0, 0, 10, 10}, 0.5f}, {{1, 0, 10, 10}, 0.9f}, {{50, 50, 10, 10}, 0.3f}, {{80, 80, 5, 5}, 0.1f}};
  const auto kept = suppress_non_maxima(boxes, 0.2, 0.1);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_FLOAT_EQ(kept[0].confidence, 0.9f);  // beats the 0.5 box (IoU 9/11 > 0.1)
  EXPECT_FLOAT_EQ(kept[1].confidence, 0.3f);  // disjoint; the 0.1 box is below the score threshold
  // A loose NMS threshold keeps both overlapping boxes.
  EXPECT_EQ(suppress_non_maxima(boxes, 0.2, 0.95).size(), 3u);
}

}  // namespace
}  // namespace crowdslam::people
