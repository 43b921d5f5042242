#pragma once
// The one way consumers follow a run (docs/ARCHITECTURE.md, "Observers"): the output journal, and later
// the viewer, the report and Python callers implement RunObserver; System calls them and never knows
// which ones there are.
//
// Calls come from the tracking thread (the caller of System::track / System::finish), in frame order.
// An observer that does real work (files, encoding, network) queues it to a thread of its own and
// returns at once; it must never call back into System. Observers are not owned and must outlive the
// System they are added to (or be removed first).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/io/dataset.h"

namespace crowdslam::system {

struct FrameReport;

// One map of a run: a map reset (tracking lost before the map could relocalise) ends a segment and the
// next frames build a new map in a new coordinate frame.
struct MapSegment {
  int map_id = 0;           // 0, 1, ... in the order the maps were built
  size_t first_frame = 0;   // frame indices covered by this map's lifetime (lost frames included)
  size_t last_frame = 0;
  size_t frames = 0;
  size_t tracked = 0;       // frames with a pose in this map
  double first_stamp_s = 0; // of the first / last frame with a pose (0 when none)
  double last_stamp_s = 0;
  size_t keyframes = 0;     // keyframes in the map when it ended (or now)
};

// How a run ended, as written to run.json: "completed", "interrupted" or "failed: <reason>".
struct EndState {
  enum class Kind { kCompleted, kInterrupted, kFailed };
  Kind kind = Kind::kCompleted;
  int signal = 0;      // kInterrupted: SIGINT, SIGTERM or SIGHUP
  std::string reason;  // kFailed: the error message
  [[nodiscard]] std::string to_string() const;
  [[nodiscard]] bool completed() const { return kind == Kind::kCompleted; }
};

// A cheap, consistent copy of the map for observers (taken under the map-update lock on the tracking
// thread, so no observer touches live map objects): point positions, keyframe poses and graph edges.
struct MapSnapshot {
  struct Point {
    uint64_t id = 0;
    float x = 0, y = 0, z = 0;
    int observations = 0;
  };
  struct Keyframe {
    uint64_t id = 0;
    double timestamp_s = 0;
    geometry::SE3 world_from_cam;
  };
  size_t frame_index = 0;  // taken after this frame
  int map_id = 0;          // segment (changes when the map is reset)
  std::vector<Point> points;
  std::vector<Keyframe> keyframes;
  std::vector<std::pair<uint64_t, uint64_t>> covisibility;  // strong edges (weight >= 100), each once
  std::vector<std::pair<uint64_t, uint64_t>> loop_edges;    // each once
  int loops_closed = 0;
};

class RunObserver {
 public:
  virtual ~RunObserver() = default;
  // After every frame. `world_from_cam` is the pose at tracking time (empty when not tracked); later
  // bundle adjustment refines it (System::camera_trajectory). `images` are the frame's input images.
  virtual void on_frame(const FrameReport& /*report*/, const std::optional<geometry::SE3>& /*world_from_cam*/,
                        const io::FrameImages& /*images*/) {}
  // Tracking created keyframe `id`.
  virtual void on_keyframe(uint64_t /*id*/) {}
  // The map was reset: `segment` is the map that ended.
  virtual void on_reset(const MapSegment& /*segment*/) {}
  // How often this observer wants a MapSnapshot, in seconds of wall time (0: never, the default). System
  // takes one snapshot for all observers that want one when the shortest interval has passed, after a
  // frame, and a last one in finish().
  [[nodiscard]] virtual double map_snapshot_interval_s() const { return 0; }
  virtual void on_map_snapshot(const std::shared_ptr<const MapSnapshot>& /*snapshot*/) {}
  // The run is over (System::finish): the threads are stopped and the final trajectories are available.
  virtual void on_finish(const EndState& /*end*/) {}
};

}  // namespace crowdslam::system
