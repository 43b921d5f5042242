#pragma once
// Short-term person tracks: boxes that persist between detections.
//
// A detector misses a person now and then and fires on a poster or a textured wall for a single frame;
// the people filter should follow people, not single detections. BoxTracker associates each new set of
// detections with its tracks by IoU (minimum-cost assignment, people/assignment.h), then:
//  - a matched track takes the detection's box and confidence;
//  - a detection matched to no track starts a tentative track, confirmed when it is detected again
//    (min_hits detections in a row) or at once when its confidence is at least confirm_confidence (a
//    clear person in the first frame must be filtered in the first frame);
//  - a confirmed track missed by a detection coasts (its box moved by the caller with the image flow,
//    people/box_flow.h) for up to max_misses detections, then ends; a tentative track missed once ends.
// boxes() returns the confirmed tracks' boxes: these are what the filter removes.
#include <cstddef>
#include <vector>

#include "crowdslam/people/box_flow.h"
#include "crowdslam/people/detector.h"

namespace crowdslam::people {

struct BoxTrackerOptions {
  double iou = 0.3;                 // a detection and a track overlapping at least this much are matched
  int min_hits = 2;                 // detections in a row that confirm a tentative track
  double confirm_confidence = 0.5;  // a detection at least this confident confirms its track at once
  int max_misses = 2;               // a confirmed track survives this many detections without a match
  void check() const;               // throws InputError naming the bad value
};

struct Track {
  int id = 0;
  FlowBox flow;    // the box (and its corners for the flow) in the current frame
  int hits = 0;    // detections matched in a row
  int misses = 0;  // detections in a row without a match
  bool confirmed = false;
};

struct TrackerUpdate {
  std::size_t matched = 0;
  std::size_t started = 0;   // new tentative (or at once confirmed) tracks
  std::size_t ended = 0;     // tracks dropped (too many misses, or tentative and missed)
  std::size_t coasting = 0;  // confirmed tracks kept without a detection this time
};

class BoxTracker {
 public:
  explicit BoxTracker(BoxTrackerOptions options = {});

  // One detector result, with its boxes in the current frame's coordinates (moved there if the detection
  // is older than the frame). Detections that start or update a track need their corners seeded by the
  // caller: the tracks whose box changed are listed by refreshed().
  TrackerUpdate update(const std::vector<PersonBox>& detections);

  // Boxes of confirmed tracks (coasting ones included).
  [[nodiscard]] std::vector<PersonBox> boxes() const;
  [[nodiscard]] const std::vector<Track>& tracks() const { return tracks_; }
  // Every live track's FlowBox (track_id set): the caller moves them with the image flow and hands
  // them back to apply_moved(); a track whose box is missing there (it left the image) ends.
  [[nodiscard]] std::vector<FlowBox> flow_boxes() const;
  void apply_moved(const std::vector<FlowBox>& moved);
  // Indices into tracks() whose boxes were set from a detection by the last update().
  [[nodiscard]] const std::vector<std::size_t>& refreshed() const { return refreshed_; }
  void clear();

 private:
  BoxTrackerOptions options_;
  std::vector<Track> tracks_;
  std::vector<std::size_t> refreshed_;
  int next_id_ = 1;
};

}  // namespace crowdslam::people
