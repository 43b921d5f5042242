#pragma once
// Global bundle adjustment after a loop correction (ORB-SLAM2's RunGlobalBundleAdjustment, our way).
//
// All keyframes and map points of the map are copied into plain BA structures and optimised (Ceres,
// optim::local_bundle_adjustment with every keyframe free except the first) without any lock held. The
// result is then applied with local mapping paused and under the map-update lock: keyframes created
// meanwhile are moved with their spanning-tree parent (their pose relative to it is kept), and points
// created meanwhile are moved with their reference keyframe.
//
// With set_ground (monocular, a vehicle's camera), each keyframe's ground points are held at the map's
// ground height too (optim::BaPlaneConstraint): the camera rides at one height, which a monocular map's
// scale drift would change.
//
// Threaded: launch() runs it in its own thread; a new loop calls abort() (the optimisation stops after its
// current iteration and nothing is applied) before correcting. Inline: run() on the caller's thread.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "crowdslam/geometry/ground_plane.h"
#include "crowdslam/loop/local_mapping_control.h"
#include "crowdslam/map/map.h"
#include "crowdslam/optim/bundle_adjustment.h"

namespace crowdslam::loop {

struct GlobalBaStats {
  int runs = 0;
  int aborted = 0;
  int applied = 0;
  double time_ms_total = 0;
  // Of the last adjustment that ran to the end (robust cost, chi2 units; solver iterations).
  double last_initial_cost = 0;
  double last_final_cost = 0;
  int last_iterations = 0;
  // Of the last adjustment with the ground (set_ground): keyframes whose ground was held, ground points
  // constrained, and the reference height (map units, before the adjustment).
  int ground_keyframes = 0;
  int ground_points = 0;
  double ground_height = 0;
};

class GlobalBundleAdjuster {
 public:
  GlobalBundleAdjuster(std::shared_ptr<map::Map> map, LocalMappingControl* mapper, int iterations = 10);
  ~GlobalBundleAdjuster();
  GlobalBundleAdjuster(const GlobalBundleAdjuster&) = delete;
  GlobalBundleAdjuster& operator=(const GlobalBundleAdjuster&) = delete;

  // Aborts a running adjustment, then starts a new one in its own thread.
  void launch();
  // Runs one adjustment on the caller's thread (sequential mode). Returns true when it was applied.
  bool run();
  // Stops a running adjustment (nothing of it is applied) and joins its thread. Idempotent.
  void abort();
  // Waits for a running adjustment to finish (and be applied).
  void wait();
  [[nodiscard]] bool is_running() const { return running_; }
  [[nodiscard]] GlobalBaStats stats() const;
  // A camera at a constant height above planar ground (a car's): every adjustment from now on also holds
  // each keyframe's ground at one height (geometry/ground_plane.h). Call before launch() or run().
  void set_ground(const geometry::GroundPlaneOptions& options);

 private:
  bool optimise_and_apply();
  std::vector<optim::BaPlaneConstraint> ground_constraints(const std::vector<std::shared_ptr<map::KeyFrame>>& keyframes,
                                                           const std::vector<std::shared_ptr<map::MapPoint>>& points);

  std::shared_ptr<map::Map> map_;
  LocalMappingControl* mapper_;
  int iterations_;
  std::optional<geometry::GroundPlaneOptions> ground_;
  std::atomic<bool> abort_{false};
  std::atomic<bool> running_{false};
  std::thread worker_;
  mutable std::mutex stats_mutex_;
  GlobalBaStats stats_;
};

}  // namespace crowdslam::loop
