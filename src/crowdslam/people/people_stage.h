#pragma once
// The people filter's part of building a frame (Crowd-SLAM's detector thread, keypoint filter and
// feature-number update): System calls begin_frame() before ORB extraction and filter() after it.
//
// Two detector modes (Detector.mode):
//  - every_frame: the detector runs on every frame, beside ORB extraction, and the frame waits for its
//    boxes (the paper's design: a slow detector slows SLAM down to its own rate). A run's reader thread
//    may start a frame's detection as soon as the frame is read (submit_ahead, System::prepare), so the
//    boxes are usually ready in the frame's turn;
//  - latest: the detector takes the newest frame whenever it is free and tracking never waits; each frame
//    uses the newest finished detection moved to it with the image motion (box_flow.h), marked as
//    propagated when the detection was made on an earlier frame.
// With Detector.tracker, detections update short-term tracks (box_tracker.h) and the filter uses
// the confirmed tracks: a box survives a missed detection or two, a one-detection box is not used unless
// it is confident.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/feature/raw_features.h"
#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/people/box_flow.h"
#include "crowdslam/people/box_tracker.h"
#include "crowdslam/people/detection_worker.h"
#include "crowdslam/people/feature_budget.h"
#include "crowdslam/people/keypoint_filter.h"

namespace crowdslam::people {

enum class DetectorMode { kEveryFrame, kLatest };
DetectorMode parse_detector_mode(const std::string& name, const std::string& key);
const char* to_string(DetectorMode mode);

struct PeopleStageOptions {
  io::SensorKind sensor = io::SensorKind::kRgbd;
  std::string detections_file;  // MOT file instead of the network
  std::string detector_model;   // overrides Detector.model_cfg
};

// What the stage did to one frame (copied into the frame's report).
struct PeopleFrame {
  int person_boxes = 0;    // boxes of people in this frame (after NMS / confirmed tracks)
  double people_area = 0;  // fraction of the image they cover (FeatureBudget.area)
  int keypoints_before_filter = 0;
  double detector_ms = 0;       // forward time of the detection whose boxes are used (0: none new)
  double detector_wait_ms = 0;  // how long the frame waited for boxes (every_frame mode only)
  int right_keypoints_removed = 0;
  int flat_boxes = 0;             // RGB-D: boxes with nothing standing out of their surroundings, ignored
  int64_t detection_frame = -1;   // frame the boxes were detected on (-1: no detection yet)
  bool boxes_propagated = false;  // boxes moved here from an earlier frame by the image flow
  std::vector<PersonBox> boxes;         // used for filtering
  std::vector<cv::KeyPoint> removed_keypoints;  // only when recording keypoints
  // When the filter removed keypoints: per keypoint before the filter, its index after it (-1 = removed)
  // and the box that removed it (index into `boxes`, -1 = kept).
  std::vector<long> filtered_index;
  std::vector<int> box_of;
};

struct PeopleStageStats {
  std::size_t detections = 0;           // detector results used
  std::size_t frames_detected = 0;      // frames whose boxes were detected on that very frame
  std::size_t frames_propagated = 0;    // frames whose boxes came from an earlier frame
  std::size_t boxes_moved = 0;          // box moves by the flow (summed over frames)
  std::size_t boxes_kept_in_place = 0;  // boxes the flow could not move (too few corners)
  std::size_t tracks_started = 0;
  std::size_t tracks_coasting = 0;  // summed over detections: confirmed tracks kept without a match
  std::size_t flat_boxes = 0;       // boxes the depth test found flat (summed over frames, NMS level)
  std::size_t frames_with_flat_boxes = 0;
  std::size_t raw_boxes_dropped = 0;  // raw boxes far larger than their NMS box, not used as masks
};

class PeopleStage {
 public:
  PeopleStage(const io::Settings& settings, const PeopleStageOptions& options);

  // Before ORB extraction of frame `index` (colour BGR or grey, `gray` its grey version): every_frame
  // submits the frame to the detector; latest moves the current boxes to this frame, takes a finished
  // detection if there is one and hands this frame to the detector when it is free.
  // `ahead_ticket`: the frame was given to the detector before its turn (submit_ahead), not again here.
  void begin_frame(std::size_t index, const cv::Mat& colour, const cv::Mat& gray,
                   std::optional<std::size_t> ahead_ticket = std::nullopt);
  // every_frame mode with a network detector: the detector may start on a frame before begin_frame(),
  // from the thread that reads the frames (System::prepare), so the frame does not wait for its boxes
  // when its turn comes. Returns the ticket for begin_frame(). The boxes are the frame's own either way.
  [[nodiscard]] bool detects_ahead() const;
  std::size_t submit_ahead(std::size_t index, const cv::Mat& colour);
  // After extraction (and stereo matching): the frame's boxes (every_frame waits for them), the keypoints
  // on people removed from `raw`, and the next frame's feature budget.
  PeopleFrame filter(std::size_t index, const io::FrameImages& images, feature::RawFeatures& raw,
                     bool record_keypoints);

  [[nodiscard]] int next_feature_budget() const { return next_feature_budget_; }
  void set_next_feature_budget(int n) { next_feature_budget_ = n; }
  [[nodiscard]] std::string detector_name() const { return worker_->detector().name(); }
  [[nodiscard]] DetectorMode mode() const { return mode_; }
  [[nodiscard]] bool tracker_enabled() const { return tracker_.has_value(); }
  [[nodiscard]] const PeopleStageStats& stats() const { return stats_; }
  [[nodiscard]] bool filter_before_nms() const { return filter_before_nms_; }  // raw boxes mask

 private:
  // A detection result in the current frame's coordinates: moved from its own frame's grey image.
  void take_detection(WorkerResult result, const FlowImage& image);
  std::optional<std::size_t> ahead_ticket_;  // this frame's, from begin_frame()
  // Boxes the filter uses now, and the ones (NMS level) that say how much of the image people cover.
  void current_boxes(std::vector<PersonBox>& filter_boxes,
                     std::vector<PersonBox>& area_boxes) const;
  // The raw boxes used as masks (Detector.raw_box_max_area_ratio); counts the ones left out.
  std::vector<PersonBox> masking_raw_boxes(const Detections& detections);
  void move_to(const FlowImage& image);
  void flow(const FlowImage& from, const FlowImage& to, std::vector<FlowBox>& boxes,
            std::vector<bool>* nms, std::vector<int>* leader);

  io::SensorKind sensor_;
  double depth_map_factor_ = 1.0;
  std::unique_ptr<DetectionWorker> worker_;
  DetectorMode mode_ = DetectorMode::kEveryFrame;
  KeypointFilterOptions filter_options_;
  FeatureBudgetOptions budget_options_;
  AreaMode area_mode_ = AreaMode::kSum;
  BoxFlowOptions flow_options_;
  std::optional<BoxTracker> tracker_;
  bool filter_before_nms_ = true;  // Settings' filter_before_nms; unset: true for RGB-D only
  double raw_box_max_area_ratio_ = 0.0;
  bool right_image_boxes_ = false;
  double flat_box_margin_m_ = 0;
  int next_feature_budget_ = 0;
  // Without the tracker, the newest detection's boxes (raw ones, with `nms_` marking those NMS kept) in
  // the frame `current_` shows (latest mode).
  std::vector<FlowBox> boxes_;
  std::vector<bool> nms_;
  std::vector<int> leader_;  // per box: the NMS box a raw box moves with (-1: moved by its own flow)
  FlowImage current_;
  FlowImage offered_;  // the frame the detector is working on (latest mode)
  std::size_t offered_index_ = 0;
  bool offered_any_ = false;
  std::size_t latest_interval_ = 1;  // Detector.latest_interval
  int64_t detection_frame_ = -1;
  double detection_ms_ = 0;  // forward time of the detection taken this frame
  bool fresh_ = false;       // a detection was taken this frame
  PeopleStageStats stats_;
};

}  // namespace crowdslam::people
