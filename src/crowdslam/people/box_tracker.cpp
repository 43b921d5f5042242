#include "crowdslam/people/box_tracker.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "crowdslam/people/assignment.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {

void BoxTrackerOptions::check() const {
  if (!(iou > 0 && iou <= 1)) throw InputError("Detector.track_iou must be in (0, 1], got " + std::to_string(iou));
  if (min_hits < 1) throw InputError("Detector.track_min_hits must be >= 1, got " + std::to_string(min_hits));
  if (!(confirm_confidence >= 0 && confirm_confidence <= 1.0000001)) {
    throw InputError("Detector.track_confirm_confidence must be in [0, 1], got " +
                     std::to_string(confirm_confidence));
  }
  if (max_misses < 0) throw InputError("Detector.track_max_misses must be >= 0, got " + std::to_string(max_misses));
}

BoxTracker::BoxTracker(BoxTrackerOptions options) : options_(options) { options_.check(); }

void BoxTracker::clear() {
  tracks_.clear();
  refreshed_.clear();
}

TrackerUpdate BoxTracker::update(const std::vector<PersonBox>& detections) {
  TrackerUpdate out;
  std::vector<std::vector<double>> similarity(tracks_.size(), std::vector<double>(detections.size(), 0.0));
  for (std::size_t t = 0; t < tracks_.size(); ++t)
    for (std::size_t d = 0; d < detections.size(); ++d)
      similarity[t][d] = box_iou(tracks_[t].flow.box.box, detections[d].box);
  const std::vector<int> match = match_by_similarity(similarity, options_.iou);

  std::vector<bool> used(detections.size(), false);
  std::vector<Track> kept;
  kept.reserve(tracks_.size() + detections.size());
  refreshed_.clear();
  for (std::size_t t = 0; t < tracks_.size(); ++t) {
    Track& track = tracks_[t];
    if (match[t] >= 0) {
      const PersonBox& d = detections[static_cast<std::size_t>(match[t])];
      used[static_cast<std::size_t>(match[t])] = true;
      track.flow.box = d;
      ++track.hits;
      track.misses = 0;
      if (track.hits >= options_.min_hits || d.confidence >= options_.confirm_confidence) track.confirmed = true;
      ++out.matched;
      refreshed_.push_back(kept.size());
      kept.push_back(std::move(track));
      continue;
    }
    ++track.misses;
    track.hits = 0;
    if (track.confirmed && track.misses <= options_.max_misses) {
      ++out.coasting;
      kept.push_back(std::move(track));
    } else {
      ++out.ended;
    }
  }
  for (std::size_t d = 0; d < detections.size(); ++d) {
    if (used[d]) continue;
    Track track;
    track.id = next_id_++;
    track.flow = FlowBox{detections[d], {}, track.id};
    track.hits = 1;
    track.confirmed = options_.min_hits <= 1 || detections[d].confidence >= options_.confirm_confidence;
    ++out.started;
    refreshed_.push_back(kept.size());
    kept.push_back(std::move(track));
  }
  tracks_ = std::move(kept);
  for (Track& t : tracks_) t.flow.track_id = t.id;
  return out;
}

std::vector<FlowBox> BoxTracker::flow_boxes() const {
  std::vector<FlowBox> out;
  out.reserve(tracks_.size());
  for (const Track& t : tracks_) out.push_back(t.flow);
  return out;
}

void BoxTracker::apply_moved(const std::vector<FlowBox>& moved) {
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (Track& t : tracks_) {
    const auto it = std::find_if(moved.begin(), moved.end(), [&](const FlowBox& f) { return f.track_id == t.id; });
    if (it == moved.end()) continue;
    t.flow = *it;
    kept.push_back(std::move(t));
  }
  tracks_ = std::move(kept);
  refreshed_.clear();
}

std::vector<PersonBox> BoxTracker::boxes() const {
  std::vector<PersonBox> out;
  for (const Track& t : tracks_)
    if (t.confirmed) out.push_back(t.flow.box);
  return out;
}

}  // namespace crowdslam::people
