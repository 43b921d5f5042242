#pragma once
// Wires the SLAM threads together: frame building (ORB) and tracking on the caller's thread, local mapping
// in its own thread (or inline in sequential mode). The only place that knows all parts.
#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/geometry/stereo_rectification.h"
#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/loop/keyframe_database.h"
#include "crowdslam/loop/loop_closer.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapping/local_mapper.h"
#include "crowdslam/people/people_stage.h"
#include "crowdslam/system/run_observer.h"
#include "crowdslam/tracking/frame_builder.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::system {

// The global BA with the ground that ends a completed monocular run on a vehicle (Ground.enabled).
struct FinalGroundBa {
  bool applied = false;  // false: fewer than 2 keyframes, or no map points (stats.ground_keyframes: 0 = no ground found)
  int keyframes = 0;
  loop::GlobalBaStats stats;  // time, costs, keyframes with ground, ground points, ground height
};

struct SystemOptions {
  io::SensorKind sensor = io::SensorKind::kRgbd;
  bool sequential = false;  // local mapping inline after each frame: reproducible runs
  // People filter and feature-number update (settings PeopleFilter.enabled can turn them off too).
  bool people_filter = true;
  // Person boxes from a MOT-format file instead of the network (frame n of the file = frame n-1 here).
  std::string detections_file;
  std::string detector_model;     // overrides Detector.model_cfg: "body", "coco", a .cfg or .onnx path
  bool record_keypoints = false;  // fill FrameReport::kept_keypoints / removed_keypoints (for drawing)
  // ORB vocabulary for place recognition (relocalisation with the keyframe database, bag-of-words
  // matching): "" = bow::default_vocabulary_path(), "none" = no vocabulary (brute-force relocalisation).
  // A missing or invalid file is an InputError naming it, thrown by the constructor.
  std::string vocabulary_path;
  // Loop closing thread (needs a vocabulary). Off: tracking, mapping and relocalisation only.
  bool loop_closing = true;
  // Backpressure (tracking/tracker.h TrackerOptions::max_wait_for_mapping_ms): how long tracking may
  // wait for local mapping to take an urgently needed keyframe. 0 = never (ORB-SLAM2).
  double max_wait_for_mapping_ms = 1000.0;
  // Monocular: wait for local mapping as sequential mode would (every due keyframe, and the next frame for
  // a keyframe's new points; TrackerOptions::monocular_replay_waits). On for unpaced replays; `crowdslam
  // run --pace sensor` turns it off, as a live camera would not wait.
  bool replay_waits_for_mapping = true;
  // Experiments and tests only: local mapping sleeps this long per keyframe (a slow mapper on demand).
  double mapper_delay_ms = 0;
  // Local mapping and loop closing run this much nicer than tracking (0-19; 0 = the same priority): when
  // every thread is busy the frame's path gets the cores first, and the mapper, getting less, makes fewer
  // keyframes (util/thread_priority.h, docs/PROFILE.md).
  int background_nice = 0;
  // prepare() also starts the person detector on the frame (every_frame mode with a network). Off for a
  // paced run, whose dropped frames would cost a detection each.
  bool prepare_detection = true;
};

// What System::prepare() did for one frame ahead of track().
struct PreparedFrame {
  feature::PreparedImage orb;                   // the left image's budget-independent extraction
  std::optional<std::size_t> detection_ticket;  // the detector started on the frame (every_frame mode)
};

// The vocabulary a System loaded, for run.json.
struct VocabularyInfo {
  std::string path;
  size_t words = 0;
  double load_ms = 0;
};

// What happened to one frame, for run.json.
struct FrameReport {
  size_t index = 0;
  double timestamp_s = 0;
  double extraction_ms = 0;
  double tracking_ms = 0;
  int keypoints = 0;
  int feature_budget = 0;
  int tracked_points = 0;
  tracking::TrackingState state = tracking::TrackingState::kNotInitialized;
  std::string method;
  bool new_keyframe = false;
  // Monocular initialisation: the earlier frames the new map gave a pose afterwards (the initializer's
  // reference frame, now the first keyframe, and those localised in the map); they count as tracked in
  // the trajectory and the summary, not in their own report.
  std::vector<size_t> localized_before_init;  // their indices
  // Monocular re-anchoring: the frames lost before it that the re-anchored map gave a pose afterwards
  // (the re-anchoring's reference frame, now a keyframe, among them); tracked in the trajectory and the
  // summary, not in their own report.
  std::vector<size_t> localized_after_reanchor;
  double waited_for_mapping_ms = 0;  // part of tracking_ms: waiting for local mapping to take a keyframe
  // People filter.
  int person_boxes = 0;
  double people_area = 0;  // fraction of the image covered (sum or union, FeatureBudget.area)
  int keypoints_before_filter = 0;
  double detector_ms = 0;         // detector forward time (runs on its own thread)
  double detector_wait_ms = 0;    // how long tracking waited for the boxes after ORB extraction
  int64_t detection_frame = -1;   // frame the boxes were detected on (-1: none yet)
  bool boxes_propagated = false;  // boxes moved here from an earlier frame (Detector.mode latest)
  // The filtered frame failed; the keypoints in boxes tracked it (Tracker::track).
  bool rescued_with_boxes = false;
  int box_matches = 0;   // tracked points that are keypoints in person boxes (Tracker::track)
  int static_boxes = 0;  // boxes the static map vouched for, their keypoints released (Tracker::track)
  // Geometric dynamic check (tracking/dynamic_check.h): keypoints judged dynamic (of them, added by region
  // growing), matches whose residual moved in this frame, map points culled as moving.
  int keypoints_dynamic = 0;
  int dynamic_grown = 0;
  int matches_moving = 0;
  int points_culled_moving = 0;
  int points_seen_through = 0;  // RGB-D: unmatched local map points the depth image sees through (free space)
  bool dynamic_check_skipped = false;  // failed with the check, tracked without it
  int right_keypoints_removed = 0;     // stereo, PeopleFilter.right_image: boxes
  int flat_boxes = 0;                  // RGB-D: boxes found flat by the depth test, not filtered
  // Stereo: kept left keypoints with a stereo match, time spent waiting for the right image's ORB
  // (extracted on a second thread) and time of the stereo matching (both included in extraction_ms).
  int stereo_matches = 0;
  double right_wait_ms = 0;
  double stereo_match_ms = 0;
  std::vector<people::PersonBox> boxes;         // used for filtering (for --save-frames)
  std::vector<cv::KeyPoint> removed_keypoints;  // only with SystemOptions::record_keypoints
  std::vector<cv::KeyPoint> kept_keypoints;
};

class System {
 public:
  System(const io::Settings& settings, const SystemOptions& options);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  // Processes one frame (colour BGR or grey; depth raw CV_16UC1 for RGB-D; right image for stereo,
  // rectified here when the settings have LEFT/RIGHT blocks). Throws InputError for a missing right image.
  // Observers see the frame before track() returns.
  FrameReport track(const io::FrameImages& images, double timestamp_s);
  // The same, with the left image's budget-independent extraction done ahead by prepare() (null: here).
  FrameReport track(const io::FrameImages& images, double timestamp_s, const PreparedFrame* prepared);
  // A frame's work that can start before its turn: the part of its ORB extraction that does not depend
  // on the feature budget (pyramid, FAST corners, blurred levels: feature/orb_extractor.h) and, with
  // SystemOptions::prepare_detection in every_frame mode, its person detection (on the detector's
  // thread). Meant for the thread that reads the frames, while track() works on an earlier one: one
  // caller thread at a time, frames in the order track() will get them (a frame prepared and then not
  // tracked, as a paced run drops, is allowed). Null when the frame is not prepared ahead (monocular;
  // stereo with rectification, whose left image changes in track(); or an image the extractor refuses:
  // track() then reports the error). track() gives the same result with or without it.
  [[nodiscard]] std::shared_ptr<const PreparedFrame> prepare(const io::FrameImages& images);
  // Lets local mapping (and loop closing) finish their queues and stops their threads (idempotent; the
  // destructor calls it).
  void shutdown();
  // Stops the threads as fast as they can: queued keyframes are dropped, running bundle adjustments
  // aborted (nothing of them applied). For interrupts: what BA already applied stays.
  void stop_now();
  // Stops the threads (shutdown() when the run completed, stop_now() otherwise) and tells the observers.
  void finish(const EndState& end);

  // Saved maps (system_map.cpp, mapdb/map_database.h). The identity a map must have to be loaded here;
  // loading one before the first frame (throws InputError for a bad file or a map that does not fit;
  // with `localization_only` tracking never creates keyframes); saving the current map (call after
  // finish(): no thread may write the map meanwhile). A loaded map's origin is kept when it is saved.
  [[nodiscard]] mapdb::MapIdentity map_identity() const;
  mapdb::LoadedMap load_map(const std::string& path, bool localization_only);
  void save_map(const std::string& path, const mapdb::MapOrigin& origin) const;
  [[nodiscard]] bool map_loaded() const { return loaded_map_origin_.has_value(); }
  [[nodiscard]] bool localization_only() const { return tracker_->localization_only(); }

  // A consistent copy of the current map (the one observers get, run_observer.h), for callers that pull
  // instead of observing (the Python API). Not synchronised with track(): call it from the tracking
  // thread, or serialise it with track(); local mapping and loop closing may run meanwhile.
  [[nodiscard]] std::shared_ptr<const MapSnapshot> map_snapshot() const { return take_map_snapshot(); }

  // Observers (not owned; see run_observer.h). Add before the first frame.
  void add_observer(RunObserver* observer) { observers_.push_back(observer); }

  // Every tracked frame of the run, over all map segments, in frame order. Poses of the current map are
  // expressed through their reference keyframe so later corrections of the keyframes propagate; poses
  // of maps that were reset are those their map had when it ended (each segment has its own frame).
  // Lost frames are left out; every frame counted as tracked has a pose here.
  [[nodiscard]] io::Trajectory camera_trajectory() const;
  // The frames bridged while people hid the view (TrackerOptions::bridge_max_s): the motion model's poses,
  // through their reference keyframe like tracked ones. Not tracked, so not in camera_trajectory().
  [[nodiscard]] io::Trajectory bridged_trajectory() const;
  [[nodiscard]] std::vector<io::Trajectory> bridged_trajectory_segments() const;  // per map segment
  // The same, one trajectory per map segment (segments().size() entries, in order).
  [[nodiscard]] std::vector<io::Trajectory> camera_trajectory_segments() const;
  // Keyframes of every map segment (earlier maps as they were when reset), in segment order.
  [[nodiscard]] io::Trajectory keyframe_trajectory() const;
  // The map segments so far (the last one is the current map).
  [[nodiscard]] std::vector<MapSegment> segments() const;
  // Frames that have a pose (== camera_trajectory().size()).
  [[nodiscard]] size_t tracked_frames() const;
  [[nodiscard]] size_t num_keyframes() const;
  [[nodiscard]] size_t num_map_points() const;
  [[nodiscard]] mapping::LocalMapperStats mapper_stats() const;
  // Empty statistics when loop closing is off.
  [[nodiscard]] loop::LoopCloserStats loop_stats() const;
  // The ground held in global BA (monocular with Ground.enabled; io::GroundSettings), else empty.
  [[nodiscard]] const std::optional<geometry::GroundPlaneOptions>& ground() const { return ground_; }
  // The global BA with the ground that ends a completed run (shutdown()); empty until it ran, when there
  // is no ground to hold, and in localisation mode (the loaded map is not changed).
  [[nodiscard]] const std::optional<FinalGroundBa>& final_ground_ba() const { return final_ground_ba_; }
  [[nodiscard]] bool loop_closing_enabled() const { return loop_closer_ != nullptr; }
  [[nodiscard]] int map_resets() const { return map_resets_; }
  // Monocular re-anchorings: a two-view map placed in the same map after a loss (method "reanchor").
  [[nodiscard]] int reanchors() const { return reanchors_; }
  [[nodiscard]] bool people_filter_enabled() const { return people_ != nullptr; }
  [[nodiscard]] std::string detector_name() const;
  // The people filter's stage (null when the filter is off).
  [[nodiscard]] const people::PeopleStage* people_stage() const { return people_.get(); }
  // Empty when running without a vocabulary.
  [[nodiscard]] const std::optional<VocabularyInfo>& vocabulary_info() const { return vocabulary_info_; }

 private:
  struct TrajectoryRecord {
    double timestamp_s = 0;
    int segment = 0;
    std::shared_ptr<map::KeyFrame> reference;  // current map only
    geometry::SE3 cam_from_reference;
    geometry::SE3 world_from_cam;  // at tracking time; after a reset, the map's final pose
    bool tracked = false;
    bool bridged = false;  // state kBridged: a pose, but not a tracked one
  };
  void reset_map();
  // Takes a MapSnapshot for the observers that want one when their interval has passed (or `force`).
  void publish_map_snapshot(bool force);
  [[nodiscard]] std::shared_ptr<const MapSnapshot> take_map_snapshot() const;
  void erase_culled_points();  // after the threads stop: bad map points out of the map
  // The record's pose through its reference keyframe (or the stored one).
  [[nodiscard]] geometry::SE3 world_from_cam(const TrajectoryRecord& record) const;
  [[nodiscard]] io::Trajectory live_keyframe_trajectory() const;
  // Reads options_.vocabulary_path into vocabulary_ (nothing for "none"); throws InputError.
  void load_vocabulary();

  io::Settings settings_;
  SystemOptions options_;
  std::shared_ptr<geometry::PinholeCamera> camera_;
  std::shared_ptr<map::Map> map_;
  std::shared_ptr<const bow::Vocabulary> vocabulary_;  // null without a vocabulary
  std::optional<VocabularyInfo> vocabulary_info_;
  std::unique_ptr<loop::KeyframeDatabase> keyframe_database_;  // with a vocabulary only
  std::unique_ptr<loop::LoopCloser> loop_closer_;              // with a vocabulary and loop closing on
  std::unique_ptr<tracking::FrameBuilder> frame_builder_;
  std::unique_ptr<geometry::StereoRectifier> rectifier_;  // stereo with LEFT/RIGHT blocks only
  std::unique_ptr<feature::ORBExtractor> preparer_;       // prepare()'s, made at its first call
  size_t prepared_frames_ = 0;                            // prepare()'s count (the detector's index)
  std::unique_ptr<mapping::LocalMapper> mapper_;
  std::unique_ptr<tracking::Tracker> tracker_;
  bool box_keypoints_ =
      false;  // the keypoints the people filter removes are offered to tracking (Tracker::BoxKeypoints)
  std::vector<TrajectoryRecord> records_;
  std::vector<MapSegment> segments_;  // the last one is the current map
  io::Trajectory past_keyframes_;     // keyframes of maps that were reset
  std::vector<RunObserver*> observers_;
  std::unique_ptr<people::PeopleStage> people_;  // null when the people filter is off
  int next_feature_budget_ = 0;
  uint64_t next_frame_id_ = 0;
  int map_resets_ = 0;
  int reanchors_ = 0;
  std::optional<mapdb::MapOrigin> loaded_map_origin_;
  std::optional<std::chrono::steady_clock::time_point> last_snapshot_;
  std::optional<geometry::GroundPlaneOptions> ground_;
  std::optional<FinalGroundBa> final_ground_ba_;
  bool shut_down_ = false;
};

// Camera model and per-module options from a settings file.
geometry::PinholeCamera camera_from_settings(const io::Settings& settings, io::SensorKind sensor);

}  // namespace crowdslam::system
