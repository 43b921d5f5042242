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

TEST(RawBoxesNearLeaders, DropsRawBoxesFarLargerThanTheirNmsBox) {
  // A 640x480 frame: a person's box (120x300) and a box spanning the whole frame, which the person's box
  // suppresses at the paper's NMS 0.1 (IoU 36000 / 307200 = 0.117).
  const PersonBox person{{260, 100, 120, 300}, 0.9f};
  const PersonBox shifted{{270, 110, 120, 300}, 0.6f};  // a neighbour of the person's box: area ratio 1
  const PersonBox tall{{250, 60, 130, 380}, 0.5f};      // ratio 49400 / 36000 = 1.37
  const PersonBox frame{{0, 0, 640, 480}, 0.3f};        // ratio 8.5
  const PersonBox other{{10, 10, 50, 60}, 0.4f};        // another person, its own NMS box
  Detections d;
  d.raw = {person, shifted, tall, frame, other};
  d.boxes = suppress_non_maxima(d.raw, 0.2, 0.1);
  ASSERT_EQ(d.boxes.size(), 2u);  // the frame-wide box was suppressed by the person's
  int dropped = -1;
  const auto kept = raw_boxes_near_leaders(d, 2.0, &dropped);
  EXPECT_EQ(dropped, 1);
  ASSERT_EQ(kept.size(), 4u);
  for (const auto& b : kept) EXPECT_NE(b.box, frame.box);
  // At ratio 1.3 the tall box (1.37) goes too; at 10 and at 0 (off) every raw box stays.
  EXPECT_EQ(raw_boxes_near_leaders(d, 1.3, &dropped).size(), 3u);
  EXPECT_EQ(dropped, 2);
  EXPECT_EQ(raw_boxes_near_leaders(d, 10.0, &dropped).size(), 5u);
  EXPECT_EQ(raw_boxes_near_leaders(d, 0.0, &dropped).size(), 5u);
  EXPECT_EQ(dropped, 0);
  // A raw box that overlaps no NMS box has no person to outline: dropped.
  d.raw.push_back({{600, 400, 20, 20}, 0.25f});
  EXPECT_EQ(raw_boxes_near_leaders(d, 2.0, &dropped).size(), 4u);
  EXPECT_EQ(dropped, 2);
}

}  // namespace
}  // namespace crowdslam::people
