#pragma once
// Wires the SLAM threads together: frame building (ORB) and tracking on the caller's thread, local mapping
// in its own thread (or inline in sequential mode). The only place that knows all parts.
#include <memory>
#include <optional>
#include <vector>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/mapping/local_mapper.h"
#include "crowdslam/tracking/frame_builder.h"
#include "crowdslam/tracking/tracker.h"

namespace crowdslam::system {

struct SystemOptions {
  io::SensorKind sensor = io::SensorKind::kRgbd;
  bool sequential = false;  // local mapping inline after each frame: reproducible runs
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
};

class System {
 public:
  System(const io::Settings& settings, const SystemOptions& options);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  // Processes one frame (colour BGR or grey; depth raw CV_16UC1 for RGB-D).
  FrameReport track(const io::FrameImages& images, double timestamp_s);
  // Lets local mapping finish and stops its thread (idempotent; the destructor calls it).
  void shutdown();

  // Every tracked frame, each pose expressed through its reference keyframe so later corrections of the
  // keyframes propagate (lost frames are left out).
  [[nodiscard]] io::Trajectory camera_trajectory() const;
  [[nodiscard]] io::Trajectory keyframe_trajectory() const;
  [[nodiscard]] size_t num_keyframes() const;
  [[nodiscard]] size_t num_map_points() const;
  [[nodiscard]] mapping::LocalMapperStats mapper_stats() const;
  [[nodiscard]] int map_resets() const { return map_resets_; }

 private:
  struct TrajectoryRecord {
    double timestamp_s = 0;
    std::shared_ptr<map::KeyFrame> reference;
    geometry::SE3 cam_from_reference;
    bool tracked = false;
  };
  void reset_map();

  io::Settings settings_;
  SystemOptions options_;
  std::shared_ptr<geometry::PinholeCamera> camera_;
  std::shared_ptr<map::Map> map_;
  std::unique_ptr<tracking::FrameBuilder> frame_builder_;
  std::unique_ptr<mapping::LocalMapper> mapper_;
  std::unique_ptr<tracking::Tracker> tracker_;
  std::vector<TrajectoryRecord> records_;
  uint64_t next_frame_id_ = 0;
  int map_resets_ = 0;
  bool shut_down_ = false;
};

// Camera model and per-module options from a settings file.
geometry::PinholeCamera camera_from_settings(const io::Settings& settings, io::SensorKind sensor);

}  // namespace crowdslam::system
