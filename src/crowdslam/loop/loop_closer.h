#pragma once
// Loop closing (ORB-SLAM2's LoopClosing, our way), in its own thread or inline (sequential mode).
//
// Per keyframe handed over by local mapping:
//  1. detect:  loop candidates from the keyframe database, those consistent over consecutive keyframes
//              first (LoopDetector);
//  2. verify:  BoW matches with each candidate -> Sim3 by RANSAC on 3D-3D matches (scale fixed for
//              RGB-D / stereo) -> more matches through the Sim3 -> Sim3 refined -> matches of the loop's
//              neighbourhood projected with the corrected pose; accepted with enough matches. A candidate
//              not yet consistent must also be confirmed by covisible keyframes (as ORB-SLAM3);
//  3. correct: local mapping paused, a running global BA aborted; the keyframe's neighbourhood moved to
//              its corrected pose (poses and points), loop points fused, essential graph optimised
//              (spanning tree + strong covisibility + loop edges), loop edge added;
//  4. global BA in its own thread (GlobalBundleAdjuster), applied with the map-update lock.
// The map-update lock is held only while corrections are written, so tracking keeps running.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "crowdslam/geometry/sim3.h"
#include "crowdslam/loop/global_ba.h"
#include "crowdslam/loop/keyframe_database.h"
#include "crowdslam/loop/local_mapping_control.h"
#include "crowdslam/loop/loop_detector.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"

namespace crowdslam::loop {

struct LoopCloserOptions {
  bool fix_scale = true;                 // RGB-D and stereo: the loop transform is rigid
  int min_keyframes_since_loop = 10;     // no detection right after a loop
  int min_map_keyframes = 10;
  int consistency_threshold = 3;
  int min_bow_matches = 20;
  int min_sim3_inliers = 20;
  int min_total_matches = 40;            // after projecting the loop's neighbourhood
  // A candidate not yet consistent over consecutive keyframes is still verified (at most
  // `immediate_candidates` of them, best score first) and accepted when, besides the keyframe itself, this
  // many of its covisible keyframes also match min_total_matches of the loop's points through the same
  // correction (ORB-SLAM3's verification in covisible keyframes: a loop is closed when it is seen, not
  // three keyframes later, which a crowd or the end of a sequence may never bring). 0 = off.
  int covisible_confirmations = 1;
  int immediate_candidates = 3;
  int essential_graph_min_weight = 100;  // covisibility edges of the essential graph
  int essential_graph_iterations = 20;
  bool global_ba = true;
  int global_ba_iterations = 10;
  // Monocular on a vehicle (io::GroundSettings): global BA also holds the ground under each keyframe.
  std::optional<geometry::GroundPlaneOptions> ground;
  // The loop closing thread's nice value above the creator's (util/thread_priority.h); the global BA
  // thread it starts inherits it.
  int thread_nice = 0;
  void check() const;
};

struct LoopEvent {
  uint64_t keyframe_id = 0;
  uint64_t loop_keyframe_id = 0;
  double timestamp_s = 0;       // of the keyframe that closed the loop
  double loop_timestamp_s = 0;  // of the keyframe it was matched to
  int matches = 0;
  double correction_ms = 0;
};

struct LoopCloserStats {
  int keyframes_checked = 0;
  int candidates_consistent = 0;
  int candidates_rejected = 0;  // consistent, but geometric verification failed
  int loops_confirmed_by_covisibles = 0;  // loops accepted before they were consistent
  std::vector<LoopEvent> loops;
  double detection_ms_total = 0;
  GlobalBaStats global_ba;
};

class LoopCloser {
 public:
  LoopCloser(const LoopCloserOptions& options, std::shared_ptr<map::Map> map, const KeyframeDatabase* database,
             LocalMappingControl* mapper);
  ~LoopCloser();
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  void start();
  // Finishes the queued keyframes, waits for a running global BA, stops the thread (idempotent).
  void stop();
  // Drops the queue, lets a loop correction in progress finish, aborts global BA, stops (interrupts).
  void stop_now();
  // Sequential mode: processes the queue on the caller's thread (global BA inline too).
  void process_all();
  void insert_keyframe(std::shared_ptr<map::KeyFrame> keyframe);
  // Drops the queue and the detection state and aborts global BA (map reset). Worker idle or stopped.
  void reset();
  [[nodiscard]] LoopCloserStats stats() const;

 private:
  struct Candidate {
    std::shared_ptr<map::KeyFrame> loop_keyframe;
    geometry::Sim3 cam_from_world;  // corrected pose of the current keyframe
    std::vector<std::shared_ptr<map::MapPoint>> matched;  // loop points per keypoint of the current keyframe
    std::vector<std::shared_ptr<map::MapPoint>> loop_points;  // points of the loop's neighbourhood
    int matches = 0;
  };

  void run();
  void process_keyframe(const std::shared_ptr<map::KeyFrame>& keyframe, bool inline_mode);
  // Geometric verification of `candidates` in turn; the first that passes is `accepted`. With
  // `confirmations` > 0 a candidate must also be confirmed by that many covisible keyframes.
  bool verify(const std::shared_ptr<map::KeyFrame>& keyframe,
              const std::vector<std::shared_ptr<map::KeyFrame>>& candidates, Candidate& accepted,
              int confirmations = 0);
  // Covisible keyframes of `keyframe` that match min_total_matches of the loop's points placed through
  // the candidate's correction (stops counting at `needed`).
  int covisible_confirmations(const map::KeyFrame& keyframe, const Candidate& candidate, int needed) const;
  void correct_loop(const std::shared_ptr<map::KeyFrame>& keyframe, const Candidate& loop);

  LoopCloserOptions options_;
  std::shared_ptr<map::Map> map_;
  const KeyframeDatabase* database_;
  LocalMappingControl* mapper_;
  LoopDetector detector_;
  GlobalBundleAdjuster global_ba_;
  uint64_t last_loop_keyframe_id_ = 0;
  bool any_loop_ = false;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<std::shared_ptr<map::KeyFrame>> queue_;
  bool stop_requested_ = false;
  std::thread worker_;

  mutable std::mutex stats_mutex_;
  LoopCloserStats stats_;
};

}  // namespace crowdslam::loop
