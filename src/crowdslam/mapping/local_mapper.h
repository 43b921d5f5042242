#pragma once
// Local mapping (ORB-SLAM2's LocalMapping, our way): takes keyframes from tracking and, per keyframe,
// registers its observations, culls recent map points, triangulates new points with its neighbours, fuses
// duplicates, runs local bundle adjustment and culls redundant keyframes.
//
// Threaded mode: start() runs a worker that sleeps on a condition variable until a keyframe arrives or
// stop() is called. Sequential mode: don't start(); the owner calls process_all() after each tracked
// frame, which makes runs reproducible.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "crowdslam/loop/local_mapping_control.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"
#include "crowdslam/optim/bundle_adjustment.h"
#include "crowdslam/tracking/keyframe_consumer.h"

namespace crowdslam::loop {
class KeyframeDatabase;
}

namespace crowdslam::mapping {

struct LocalMapperOptions {
  bool monocular = false;
  double close_depth_m = 3.0;         // ThDepth in metres: only close points vote in keyframe culling
  int triangulation_neighbours = 10;  // 20 for monocular
  double redundancy_ratio = 0.9;      // keyframe culling: fraction of points seen by 3+ other keyframes
  bool local_ba = true;
  // Local BA window: the new keyframe and at most this many of its best covisible keyframes, plus at most
  // this many fixed keyframes (those that see most of the window's points). ORB-SLAM2 takes all of them;
  // after a loop merges two passes over a place that becomes hundreds (see docs/ARCHITECTURE.md).
  int max_local_ba_keyframes = 25;
  // Local BA keeps a keyframe's tracked pose relative to the keyframe before it (KeyFrame::odometry) with
  // this rotation sigma (degrees; translation: the angle times the keyframe's median depth); 0 = off.
  double odometry_sigma_deg = 0;
  optim::BundleAdjustmentOptions ba;
  double delay_ms = 0;  // experiments and tests: sleep this long per keyframe (an artificially slow mapper)
  int thread_nice = 0;  // the mapper thread's nice value above the creator's (util/thread_priority.h)
  void check() const;
};

// Time of each step for one keyframe (ms); ba_ms is 0 when local BA did not run for it.
struct KeyframeStepTimes {
  double register_ms = 0;
  double triangulation_ms = 0;
  double fusion_ms = 0;
  double ba_ms = 0;
  double culling_ms = 0;
  double total_ms = 0;
};

struct LocalMapperStats {
  int keyframes_processed = 0;
  int points_created = 0;
  int points_culled = 0;
  int keyframes_culled = 0;
  int ba_runs = 0;
  int ba_aborted = 0;
  // Tracked relative poses between keyframes (KeyFrame::odometry) held in local BAs, summed over runs.
  int ba_relative_poses = 0;
  double ba_time_ms_total = 0;
  // Time per step over all keyframes (ms).
  double register_ms_total = 0;
  double triangulation_ms_total = 0;
  double fusion_ms_total = 0;
  double culling_ms_total = 0;
  double processing_ms_total = 0;
  std::vector<KeyframeStepTimes> per_keyframe;  // in processing order (for medians and p95)
};

class LocalMapper : public tracking::KeyframeConsumer, public loop::LocalMappingControl {
 public:
  LocalMapper(const LocalMapperOptions& options, std::shared_ptr<map::Map> map);
  ~LocalMapper() override;
  LocalMapper(const LocalMapper&) = delete;
  LocalMapper& operator=(const LocalMapper&) = delete;

  // Threaded mode.
  void start();
  // Finishes the queued keyframes, then stops the worker (idempotent).
  void stop();
  // Drops the queued keyframes, aborts a running local BA (nothing of it is applied) and stops the worker
  // after the keyframe it is on (interrupts).
  void stop_now();

  // Sequential mode: processes every queued keyframe on the caller's thread.
  void process_all();

  // KeyframeConsumer.
  void insert_keyframe(std::shared_ptr<map::KeyFrame> keyframe) override;
  void insert_keyframes(std::shared_ptr<map::KeyFrame> first, std::shared_ptr<map::KeyFrame> second) override;
  [[nodiscard]] bool accepts_keyframes() const override;
  [[nodiscard]] size_t queued_keyframes() const override;
  bool wait_until_accepting(double timeout_ms) override;
  void interrupt_bundle_adjustment() override;
  [[nodiscard]] bool is_paused() const override { return pause_requested_; }

  // LocalMappingControl (loop closing): pause after the current keyframe, wait, resume.
  void request_pause() override;
  void wait_until_paused() override;
  void resume() override;

  // Called (on the mapping thread) with every keyframe that survived processing: the hand-over to loop
  // closing.
  void set_keyframe_done(std::function<void(const std::shared_ptr<map::KeyFrame>&)> keyframe_done) {
    keyframe_done_ = std::move(keyframe_done);
  }

  // Keyframes that have a bag of words are added to `database` once processed (optional; not owned). Set
  // before start().
  void set_keyframe_database(loop::KeyframeDatabase* database) { database_ = database; }

  // Drops queued keyframes and recent points (after a map reset). Call with the worker idle or stopped.
  void reset();
  [[nodiscard]] LocalMapperStats stats() const;

 private:
  void run();
  // The waits' common end (queue_mutex_ held): idle with an empty queue, or no worker, stopping or paused.
  [[nodiscard]] bool idle_or_not_working() const;
  std::shared_ptr<map::KeyFrame> next_keyframe();
  void process_keyframe(const std::shared_ptr<map::KeyFrame>& keyframe);
  void register_keyframe(const std::shared_ptr<map::KeyFrame>& keyframe);
  void cull_recent_points(const std::shared_ptr<map::KeyFrame>& keyframe);
  void create_new_points(const std::shared_ptr<map::KeyFrame>& keyframe);
  void fuse_with_neighbours(const std::shared_ptr<map::KeyFrame>& keyframe);
  void run_local_bundle_adjustment(const std::shared_ptr<map::KeyFrame>& keyframe);
  void cull_keyframes(const std::shared_ptr<map::KeyFrame>& keyframe);
  [[nodiscard]] bool has_new_keyframes() const;

  LocalMapperOptions options_;
  std::shared_ptr<map::Map> map_;
  loop::KeyframeDatabase* database_ = nullptr;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<std::shared_ptr<map::KeyFrame>> queue_;
  bool stop_requested_ = false;
  std::atomic<bool> pause_requested_{false};
  bool paused_ = false;         // the worker is waiting in a pause (queue_mutex_)
  bool worker_active_ = false;  // the worker thread is running (queue_mutex_)
  std::condition_variable paused_cv_;
  std::condition_variable idle_cv_;  // the worker finished its queue and waits for keyframes
  std::function<void(const std::shared_ptr<map::KeyFrame>&)> keyframe_done_;
  std::atomic<bool> accepting_{true};
  std::atomic<bool> abort_ba_{false};
  std::atomic<bool> stopping_now_{false};  // stop_now(): no new local BA
  std::thread worker_;

  // Owned by the mapping thread (or the caller in sequential mode).
  std::vector<std::shared_ptr<map::MapPoint>> recent_points_;
  mutable std::mutex stats_mutex_;
  LocalMapperStats stats_;
};

}  // namespace crowdslam::mapping
