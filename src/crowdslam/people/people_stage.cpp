#include "crowdslam/people/people_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "crowdslam/people/box_depth.h"
#include "crowdslam/people/detector_setup.h"
#include "crowdslam/people/dnn_detector.h"
#include "crowdslam/people/mot_file_detector.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {
constexpr double kFlatTestMinArea = 0.1;  // fraction of the image (see PeopleStage::filter)

constexpr double kSparseDepthFactor = 1000.0;  // millimetres in the stereo sparse depth image

// CV_16UC1 image (depth * factor, 0 = none) with each keypoint's stereo depth written into a square
// block. estimate_person_depth samples a box every sqrt(area / 2000) pixels; blocks that wide are
// sampled at least once, so every keypoint in a box's centre counts.
cv::Mat sparse_depth_image(const std::vector<cv::KeyPoint>& keys, const std::vector<float>& depth_m,
                           cv::Size size, double factor) {
  cv::Mat image(size, CV_16UC1, cv::Scalar(0));
  const int side = std::max(1, static_cast<int>(std::ceil(std::sqrt(size.area() / 2000.0))));
  const cv::Rect inside(0, 0, size.width, size.height);
  for (size_t i = 0; i < keys.size(); ++i) {
    const double value = depth_m[i] * factor;
    if (!(value > 0) || value > 65535) continue;
    const cv::Rect block =
        cv::Rect(cvRound(keys[i].pt.x) - side / 2, cvRound(keys[i].pt.y) - side / 2, side, side) & inside;
    if (block.area() > 0) image(block).setTo(static_cast<uint16_t>(value));
  }
  return image;
}

std::unique_ptr<PersonDetector> make_detector(const io::Settings& settings,
                                                      const PeopleStageOptions& options) {
  DetectorSetup setup = detector_setup(settings.detector, options.detector_model);
  if (!options.detections_file.empty()) {
    return std::make_unique<MotFileDetector>(options.detections_file, setup.options);
  }
  return std::make_unique<DnnDetector>(setup.model, setup.options);
}

}  // namespace

DetectorMode parse_detector_mode(const std::string& name, const std::string& key) {
  if (name == "every_frame") return DetectorMode::kEveryFrame;
  if (name == "latest") return DetectorMode::kLatest;
  throw InputError(key + ": unknown detector mode '" + name + "' (expected every_frame or latest)");
}

const char* to_string(DetectorMode mode) { return mode == DetectorMode::kLatest ? "latest" : "every_frame"; }

PeopleStage::PeopleStage(const io::Settings& settings, const PeopleStageOptions& options)
    : sensor_(options.sensor),
      depth_map_factor_(settings.depth_map_factor > 0 ? settings.depth_map_factor : 1.0),
      worker_(std::make_unique<DetectionWorker>(make_detector(settings, options))) {
  mode_ = parse_detector_mode(settings.detector.mode, "Detector.mode");
  latest_interval_ = static_cast<std::size_t>(std::max(1, settings.detector.latest_interval));
  if (settings.detector.tracker) {
    BoxTrackerOptions t;
    t.iou = settings.detector.track_iou;
    t.min_hits = settings.detector.track_min_hits;
    t.max_misses = settings.detector.track_max_misses;
    t.confirm_confidence = settings.detector.track_confirm_confidence;
    tracker_.emplace(t);
  }
  filter_options_.mode = parse_filter_mode(settings.people_filter.mode, "PeopleFilter.mode");
  filter_options_.margin_px = settings.people_filter.margin_px;
  filter_options_.depth_margin_m = settings.people_filter.depth_margin_m;
  filter_options_.silhouettes = settings.people_filter.silhouettes;
  filter_options_.segment_from_m = settings.people_filter.segment_from_m;
  // Dense depth holds the person wherever they are in the box; stereo's sparse depths hold mismatches, so
  // a low quantile there may be one of them.
  filter_options_.person_depth_quantile = sensor_ == io::SensorKind::kRgbd ? 0.1 : 0.3;
  filter_options_.check();
  right_image_boxes_ = settings.people_filter.right_image == "boxes";
  flat_box_margin_m_ = settings.people_filter.flat_box_margin_m;
  filter_before_nms_ = settings.detector.filter_before_nms.value_or(sensor_ == io::SensorKind::kRgbd);
  raw_box_max_area_ratio_ = settings.detector.raw_box_max_area_ratio;
  budget_options_.base_features = settings.orb.n_features;
  budget_options_.enabled = settings.feature_budget.enabled;
  budget_options_.thresholds = settings.feature_budget.thresholds;
  budget_options_.factors = settings.feature_budget.factors;
  area_mode_ = settings.feature_budget.area == "union" ? AreaMode::kUnion : AreaMode::kSum;
  spdlog::info("people detector {}: mode {}, tracker {}", worker_->detector().name(), to_string(mode_),
               tracker_ ? "on" : "off");
}

namespace {
// Seeds new corners in the boxes tracked by their own flow (no leader; all boxes when `leader` is null):
// every such box, or with `only_thin` those with few corners left (lost to occlusion and the
// forward-backward check).
void seed_corners(const cv::Mat& gray, std::vector<FlowBox>& boxes, const std::vector<int>* leader,
                  const BoxFlowOptions& options, bool only_thin) {
  std::vector<size_t> index;
  std::vector<FlowBox> seeded;
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (leader != nullptr && (*leader)[i] >= 0) continue;
    if (only_thin && static_cast<int>(boxes[i].points.size()) >= 2 * options.min_points) continue;
    index.push_back(i);
    seeded.push_back(boxes[i]);
  }
  if (seeded.empty()) return;
  seed_points(gray, seeded, options);
  for (size_t k = 0; k < index.size(); ++k) boxes[index[k]].points = std::move(seeded[k].points);
}

// For raw boxes: the NMS box each one follows (the kept box it overlaps most), -1 for the kept boxes
// themselves and for a raw box that overlaps none.
std::vector<int> leaders_of(const std::vector<FlowBox>& boxes, const std::vector<bool>& nms) {
  std::vector<PersonBox> kept;
  std::vector<int> kept_index;
  for (size_t k = 0; k < boxes.size(); ++k) {
    if (!nms[k]) continue;
    kept.push_back(boxes[k].box);
    kept_index.push_back(static_cast<int>(k));
  }
  std::vector<int> leader(boxes.size(), -1);
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (nms[i]) continue;
    const int k = most_overlapping(boxes[i].box.box, kept);
    if (k >= 0) leader[i] = kept_index[static_cast<size_t>(k)];
  }
  return leader;
}
}  // namespace

// Moves `boxes` from `from` to `to`: boxes without a leader by the flow of their corners, the others
// (raw boxes) by their leader's motion. `nms` and `leader` (one entry per box, may be null) follow their
// boxes; a box that leaves the image is removed.
void PeopleStage::flow(const FlowImage& from, const FlowImage& to,
                       std::vector<FlowBox>& boxes, std::vector<bool>* nms,
                       std::vector<int>* leader) {
  const auto has_leader = [&](size_t i) { return leader != nullptr && (*leader)[i] >= 0; };
  std::vector<FlowBox> tracked;
  std::vector<cv::Point2f> centre(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    const cv::Rect2f& r = boxes[i].box.box;
    centre[i] = cv::Point2f(r.x + 0.5f * r.width, r.y + 0.5f * r.height);
    if (has_leader(i)) continue;
    tracked.push_back(boxes[i]);
    tracked.back().track_id = static_cast<int>(i);  // the original index, restored below
  }
  std::vector<BoxMotion> tracked_motion;
  const FlowStats s = move_boxes(from, to, tracked, flow_options_, &tracked_motion);
  stats_.boxes_moved += s.boxes_moved;
  stats_.boxes_kept_in_place += s.boxes_kept;
  std::vector<BoxMotion> motion(boxes.size());
  for (size_t i = 0, k = 0; i < boxes.size(); ++i) {
    if (!has_leader(i)) motion[i] = tracked_motion[k++];
  }
  std::vector<std::optional<FlowBox>> moved(boxes.size());
  for (auto& b : tracked) {
    const auto original = static_cast<size_t>(b.track_id);
    b.track_id = boxes[original].track_id;
    moved[original] = std::move(b);
  }
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (!has_leader(i)) continue;
    const auto l = static_cast<size_t>((*leader)[i]);
    const cv::Rect2f r =
        follow_motion(boxes[i].box.box, centre[l], motion[l], to.gray.cols, to.gray.rows);
    if (!(r.width > 0) || !(r.height > 0)) continue;
    moved[i] = boxes[i];
    moved[i]->box.box = r;
    if (motion[l].moved) ++stats_.boxes_moved;
  }
  std::vector<int> new_index(boxes.size(), -1);
  std::vector<FlowBox> out;
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (!moved[i]) continue;
    new_index[i] = static_cast<int>(out.size());
    out.push_back(std::move(*moved[i]));
  }
  std::vector<bool> flags;
  std::vector<int> leaders;
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (new_index[i] < 0) continue;
    if (nms != nullptr && !nms->empty()) flags.push_back((*nms)[i]);
    if (leader != nullptr)
      leaders.push_back(has_leader(i) ? new_index[static_cast<size_t>((*leader)[i])] : -1);
  }
  boxes = std::move(out);
  if (nms != nullptr) *nms = std::move(flags);
  if (leader != nullptr) *leader = std::move(leaders);
}

void PeopleStage::move_to(const FlowImage& image) {
  if (!current_.empty() && current_.gray.size() == image.gray.size() &&
      current_.gray.data != image.gray.data) {
    if (tracker_) {
      std::vector<FlowBox> boxes = tracker_->flow_boxes();
      if (!boxes.empty()) {
        flow(current_, image, boxes, nullptr, nullptr);
        seed_corners(image.gray, boxes, nullptr, flow_options_, true);
        tracker_->apply_moved(boxes);
      }
    } else if (!boxes_.empty()) {
      flow(current_, image, boxes_, &nms_, &leader_);
      seed_corners(image.gray, boxes_, &leader_, flow_options_, true);
    }
  }
  current_ = image;
}

void PeopleStage::take_detection(WorkerResult result, const FlowImage& image) {
  ++stats_.detections;
  fresh_ = true;
  detection_frame_ = static_cast<int64_t>(result.frame_index);
  detection_ms_ = result.detections.time_ms;
  const bool use_raw = filter_before_nms_ && !tracker_;
  std::vector<FlowBox> detected =
      to_flow_boxes(use_raw ? masking_raw_boxes(result.detections) : result.detections.boxes);
  std::vector<bool> nms(detected.size(), true);
  if (use_raw) {
    for (size_t i = 0; i < detected.size(); ++i) {
      const auto& box = detected[i].box.box;
      nms[i] = std::any_of(result.detections.boxes.begin(), result.detections.boxes.end(),
                           [&](const PersonBox& b) { return b.box == box; });
    }
  }
  // Raw boxes move with the NMS box they overlap most: the flow is computed for the few NMS boxes only.
  std::vector<int> leader = leaders_of(detected, nms);
  // Latest mode: the detection was made on an earlier frame; move it from that frame's image to this one.
  const bool older = mode_ == DetectorMode::kLatest && !offered_.empty() &&
                     offered_.gray.size() == image.gray.size() && offered_.gray.data != image.gray.data;
  if (older) {
    seed_corners(offered_.gray, detected, &leader, flow_options_, false);
    flow(offered_, image, detected, &nms, &leader);
  }
  if (tracker_) {
    const TrackerUpdate u = tracker_->update(to_person_boxes(detected));
    stats_.tracks_started += u.started;
    stats_.tracks_coasting += u.coasting;
    std::vector<FlowBox> boxes = tracker_->flow_boxes();
    std::vector<FlowBox> refreshed;
    for (size_t i : tracker_->refreshed()) refreshed.push_back(boxes[i]);
    seed_points(image.gray, refreshed, flow_options_);
    for (size_t k = 0; k < refreshed.size(); ++k)
      boxes[tracker_->refreshed()[k]].points = refreshed[k].points;
    tracker_->apply_moved(boxes);
  } else {
    // The moved boxes keep the corners that followed them; boxes left with few (or none, when the
    // detection is this frame's own) get new ones here.
    if (mode_ == DetectorMode::kLatest) seed_corners(image.gray, detected, &leader, flow_options_, true);
    boxes_ = std::move(detected);
    nms_ = std::move(nms);
    leader_ = std::move(leader);
  }
}

bool PeopleStage::detects_ahead() const {
  return mode_ == DetectorMode::kEveryFrame && worker_->detector().reads_pixels();
}

std::size_t PeopleStage::submit_ahead(std::size_t index, const cv::Mat& colour) {
  if (!detects_ahead())
    throw std::logic_error("PeopleStage::submit_ahead: not in every_frame mode with a network");
  return worker_->submit_ahead(index, colour);
}

void PeopleStage::begin_frame(std::size_t index, const cv::Mat& colour, const cv::Mat& gray,
                              std::optional<std::size_t> ahead_ticket) {
  fresh_ = false;
  detection_ms_ = 0;
  ahead_ticket_.reset();
  if (mode_ == DetectorMode::kEveryFrame) {
    if (ahead_ticket) {
      ahead_ticket_ = ahead_ticket;
    } else {
      worker_->submit(index, colour);
    }
    if (tracker_) move_to(make_flow_image(gray, flow_options_));  // coasting tracks follow the image
    return;
  }
  const FlowImage image = make_flow_image(gray, flow_options_);
  move_to(image);
  if (auto result = worker_->poll()) take_detection(std::move(*result), image);
  const bool due = !offered_any_ || index >= offered_index_ + latest_interval_;
  if (due && worker_->offer(index, colour)) {
    offered_ = image;
    offered_index_ = index;
    offered_any_ = true;
  }
}

std::vector<PersonBox> PeopleStage::masking_raw_boxes(const Detections& detections) {
  int dropped = 0;
  std::vector<PersonBox> raw =
      raw_boxes_near_leaders(detections, raw_box_max_area_ratio_, &dropped);
  stats_.raw_boxes_dropped += static_cast<std::size_t>(dropped);
  return raw;
}

void PeopleStage::current_boxes(std::vector<PersonBox>& filter_boxes,
                                std::vector<PersonBox>& area_boxes) const {
  filter_boxes.clear();
  area_boxes.clear();
  if (tracker_) {
    filter_boxes = tracker_->boxes();
    area_boxes = filter_boxes;
    return;
  }
  for (size_t i = 0; i < boxes_.size(); ++i) {
    filter_boxes.push_back(boxes_[i].box);
    if (nms_[i]) area_boxes.push_back(boxes_[i].box);
  }
}

PeopleFrame PeopleStage::filter(std::size_t index, const io::FrameImages& images, feature::RawFeatures& raw,
                                bool record_keypoints) {
  PeopleFrame out;
  std::vector<PersonBox> boxes, area_boxes;
  if (mode_ == DetectorMode::kEveryFrame) {
    WorkerResult result = ahead_ticket_ ? worker_->wait_ahead(*ahead_ticket_) : worker_->wait(index);
    ahead_ticket_.reset();
    out.detector_wait_ms = result.waited_ms;
    if (tracker_) {
      take_detection(std::move(result), current_);
      current_boxes(boxes, area_boxes);
    } else {
      // The paper's path, unchanged: this frame's own boxes.
      ++stats_.detections;
      fresh_ = true;
      detection_frame_ = static_cast<int64_t>(index);
      detection_ms_ = result.detections.time_ms;
      boxes = filter_before_nms_ ? masking_raw_boxes(result.detections) : result.detections.boxes;
      area_boxes = result.detections.boxes;
    }
  } else {
    current_boxes(boxes, area_boxes);
  }
  out.detector_ms = detection_ms_;
  out.detection_frame = detection_frame_;
  out.boxes_propagated = detection_frame_ >= 0 && detection_frame_ != static_cast<int64_t>(index);
  if (detection_frame_ == static_cast<int64_t>(index)) ++stats_.frames_detected;
  if (out.boxes_propagated) ++stats_.frames_propagated;
  const bool rgbd = sensor_ == io::SensorKind::kRgbd && !images.depth.empty();
  std::vector<float> depth_m;
  if (filter_options_.mode == FilterMode::kDepth && rgbd) {
    depth_m.resize(raw.keys.size(), -1.0f);
    for (size_t i = 0; i < raw.keys.size(); ++i) {
      const int x = cvRound(raw.keys[i].pt.x);
      const int y = cvRound(raw.keys[i].pt.y);
      if (x < 0 || y < 0 || x >= images.depth.cols || y >= images.depth.rows) continue;
      const uint16_t d = images.depth.at<uint16_t>(y, x);
      if (d > 0) depth_m[i] = static_cast<float>(d / depth_map_factor_);
    }
  }
  // Stereo: the keypoints' depths come from stereo matching, which runs before the filter; each person's
  // depth (and the flat-box test) works on them through a sparse depth image.
  cv::Mat stereo_depth;
  const bool stereo = sensor_ == io::SensorKind::kStereo && raw.depth_m.size() == raw.keys.size();
  const bool depth_mode = filter_options_.mode == FilterMode::kDepth;
  if (stereo && !boxes.empty() && (depth_mode || flat_box_margin_m_ > 0)) {
    if (depth_mode) depth_m = raw.depth_m;
    stereo_depth = sparse_depth_image(raw.keys, raw.depth_m, images.colour.size(), kSparseDepthFactor);
  }
  const double depth_factor = stereo ? kSparseDepthFactor : depth_map_factor_;
  const cv::Mat& depth_image = rgbd ? images.depth : stereo_depth;
  if (!depth_image.empty() && flat_box_margin_m_ > 0 && !area_boxes.empty()) {
    // Boxes on a flat surface (a poster, a wall photograph): nothing stands in front of what surrounds
    // them, so they hold no person to filter (people/box_depth.h). Each raw box is tested on its own.
    // Boxes under a tenth of the image are left alone: they cost tracking little, and that is where the
    // test misjudges people (partly in view at the image's edge, or far away among others).
    const double min_area = kFlatTestMinArea * depth_image.cols * depth_image.rows;
    // The NMS boxes are among the raw boxes too: each box is tested once.
    std::vector<std::pair<cv::Rect2f, BoxDepthVerdict>> tested;
    // RGB-D: the NMS boxes, so that a person is not found flat on the people beside them alone
    // (box_depth.h). Not in stereo, whose sparse depth around a large false positive over people
    // showed mostly those people: judged again without them it was undecided and kept, and hid the map.
    std::vector<cv::Rect2f> people;
    if (rgbd) {
      for (const auto& b : area_boxes) people.push_back(b.box);
    }
    auto verdict = [&](const PersonBox& b) {
      if (b.box.area() < min_area) return BoxDepthVerdict::kUnknown;
      for (const auto& [box, v] : tested) {
        if (box == b.box) return v;
      }
      const auto v = box_depth_test(depth_image, depth_factor, b.box, flat_box_margin_m_, people).verdict;
      tested.emplace_back(b.box, v);
      return v;
    };
    // A raw box is flat when it is found flat itself or when the NMS box it duplicates is
    // (flat_by_leader).
    const std::vector<PersonBox> nms_boxes = area_boxes;
    std::vector<BoxDepthVerdict> nms_verdicts;
    for (const auto& b : nms_boxes) nms_verdicts.push_back(verdict(b));
    auto flat = [&](const PersonBox& b) {
      return flat_by_leader(b.box, verdict(b), nms_boxes, nms_verdicts);
    };
    const size_t before = area_boxes.size();
    area_boxes.erase(std::remove_if(area_boxes.begin(), area_boxes.end(), flat), area_boxes.end());
    out.flat_boxes = static_cast<int>(before - area_boxes.size());
    boxes.erase(std::remove_if(boxes.begin(), boxes.end(), flat), boxes.end());
    stats_.flat_boxes += static_cast<size_t>(out.flat_boxes);
    if (out.flat_boxes > 0) ++stats_.frames_with_flat_boxes;
  }
  out.person_boxes = static_cast<int>(area_boxes.size());
  out.keypoints_before_filter = static_cast<int>(raw.keys.size());
  // The person's surface needs dense depth: RGB-D only (stereo's depth image is its keypoints').
  KeypointFilterOptions filter_options = filter_options_;
  if (!rgbd) filter_options.segment_from_m = 0;
  const FilterResult filtered =
      filter_keypoints(raw.keys, boxes, filter_options, depth_m, depth_image, depth_factor);
  if (filtered.removed > 0) {
    feature::RawFeatures kept;
    kept.keys.reserve(raw.keys.size() - static_cast<size_t>(filtered.removed));
    kept.descriptors.create(static_cast<int>(raw.keys.size()) - filtered.removed, raw.descriptors.cols,
                            raw.descriptors.type());
    int row = 0;
    out.filtered_index.assign(raw.keys.size(), -1);
    out.box_of = filtered.box;
    for (size_t i = 0; i < raw.keys.size(); ++i) {
      if (filtered.keep[i]) {
        out.filtered_index[i] = row;
        raw.descriptors.row(static_cast<int>(i)).copyTo(kept.descriptors.row(row++));
        kept.keys.push_back(raw.keys[i]);
        if (stereo) {
          kept.right_u.push_back(raw.right_u[i]);
          kept.depth_m.push_back(raw.depth_m[i]);
        }
      } else if (record_keypoints) {
        out.removed_keypoints.push_back(raw.keys[i]);
      }
    }
    raw = std::move(kept);
  }
  if (stereo && right_image_boxes_) {
    // The boxes are the left image's, used unshifted on the right image.
    for (size_t i = 0; i < raw.keys.size(); ++i) {
      if (raw.right_u[i] < 0) continue;
      const cv::Point2f right(raw.right_u[i], raw.keys[i].pt.y);
      for (const auto& box : boxes) {
        if (box.box.contains(right)) {
          raw.right_u[i] = -1.0f;
          raw.depth_m[i] = -1.0f;
          ++out.right_keypoints_removed;
          break;
        }
      }
    }
  }
  // Feature number update for the next frame. The covered area always comes from NMS-level boxes: the
  // raw boxes overlap heavily, and their summed area says nothing about how much of the image people cover.
  budget_options_.image_width = images.colour.cols;
  budget_options_.image_height = images.colour.rows;
  out.people_area = covered_fraction(area_boxes, images.colour.cols, images.colour.rows, area_mode_);
  next_feature_budget_ = feature_budget(out.people_area, budget_options_);
  out.boxes = std::move(boxes);
  return out;
}

}  // namespace crowdslam::people
