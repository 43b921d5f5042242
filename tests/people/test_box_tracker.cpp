// Short-term box tracks: a person missed by one detection keeps their box, a low-confidence box seen once
// is never used, a confident one is used at once, tracks end after max_misses detections.
#include <gtest/gtest.h>

#include "crowdslam/people/box_tracker.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

PersonBox box(float x, float y, float w, float h, float confidence) { return PersonBox{cv::Rect2f(x, y, w, h), confidence}; }

TEST(BoxTracker, KeepsAPersonThroughMissedDetections) {
  BoxTracker tracker(BoxTrackerOptions{0.3, 2, 0.9, 2});
  tracker.update({box(100, 100, 50, 120, 0.6f)});
  EXPECT_TRUE(tracker.boxes().empty()) << "tentative after one detection";
  tracker.update({box(104, 100, 50, 120, 0.6f)});
  ASSERT_EQ(tracker.boxes().size(), 1u) << "confirmed by the second";
  EXPECT_EQ(tracker.boxes()[0].box, cv::Rect2f(104, 100, 50, 120));
  // Two missed detections: the box is still there (coasting), the third miss ends the track.
  TrackerUpdate u = tracker.update({});
  EXPECT_EQ(u.coasting, 1u);
  ASSERT_EQ(tracker.boxes().size(), 1u);
  EXPECT_EQ(tracker.boxes()[0].box, cv::Rect2f(104, 100, 50, 120));
  tracker.update({});
  EXPECT_EQ(tracker.boxes().size(), 1u);
  u = tracker.update({});
  EXPECT_EQ(u.ended, 1u);
  EXPECT_TRUE(tracker.boxes().empty());
}

TEST(BoxTracker, DropsALowConfidenceBoxSeenOnce) {
  BoxTracker tracker(BoxTrackerOptions{0.3, 2, 0.5, 2});
  tracker.update({box(10, 10, 40, 80, 0.3f)});
  EXPECT_TRUE(tracker.boxes().empty());
  const TrackerUpdate u = tracker.update({box(400, 200, 40, 80, 0.3f)});  // somewhere else
  EXPECT_EQ(u.ended, 1u);
  EXPECT_EQ(u.started, 1u);
  EXPECT_TRUE(tracker.boxes().empty());
  EXPECT_EQ(tracker.tracks().size(), 1u);
}

TEST(BoxTracker, ConfidentBoxIsUsedAtOnce) {
  BoxTracker tracker(BoxTrackerOptions{0.3, 2, 0.5, 2});
  tracker.update({box(10, 10, 40, 80, 0.7f), box(300, 10, 40, 80, 0.2f)});
  ASSERT_EQ(tracker.boxes().size(), 1u);
  EXPECT_EQ(tracker.boxes()[0].box.x, 10.0f);
}

TEST(BoxTracker, AssociatesByIouAndKeepsIdentities) {
  BoxTracker tracker(BoxTrackerOptions{0.3, 1, 0.5, 1});
  tracker.update({box(0, 0, 100, 200, 0.6f), box(300, 0, 100, 200, 0.6f)});
  ASSERT_EQ(tracker.tracks().size(), 2u);
  const int left = tracker.tracks()[0].id;
  // Reported in the other order and moved a little: matched by overlap, not by position in the list.
  const TrackerUpdate u = tracker.update({box(310, 5, 100, 200, 0.6f), box(8, 3, 100, 200, 0.6f)});
  EXPECT_EQ(u.matched, 2u);
  EXPECT_EQ(u.started, 0u);
  ASSERT_EQ(tracker.tracks().size(), 2u);
  for (const Track& t : tracker.tracks()) {
    EXPECT_EQ(t.flow.box.box.x, t.id == left ? 8.0f : 310.0f);
    EXPECT_EQ(t.flow.track_id, t.id);
  }
  // A box that overlaps neither enough starts a third track.
  EXPECT_EQ(tracker.update({box(150, 300, 50, 100, 0.6f)}).started, 1u);
}

TEST(BoxTracker, MovedBoxesComeBackAndLostOnesEnd) {
  BoxTracker tracker(BoxTrackerOptions{0.3, 1, 0.5, 2});
  tracker.update({box(0, 0, 100, 200, 0.6f), box(300, 0, 100, 200, 0.6f)});
  std::vector<FlowBox> moved = tracker.flow_boxes();
  moved[0].box.box.x += 5;
  moved.pop_back();  // the second left the image
  tracker.apply_moved(moved);
  ASSERT_EQ(tracker.boxes().size(), 1u);
  EXPECT_EQ(tracker.boxes()[0].box.x, 5.0f);
}

TEST(BoxTracker, OptionsAreChecked) {
  EXPECT_THROW(BoxTracker(BoxTrackerOptions{0.0, 2, 0.5, 2}), InputError);
  EXPECT_THROW(BoxTracker(BoxTrackerOptions{0.3, 0, 0.5, 2}), InputError);
  EXPECT_THROW(BoxTracker(BoxTrackerOptions{0.3, 2, 0.5, -1}), InputError);
}

}  // namespace
}  // namespace crowdslam::people
