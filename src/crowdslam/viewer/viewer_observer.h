#pragma once
// The live viewer's RunObserver: on the tracking thread it only copies what a message needs (decimated:
// status at most every frame_interval_s, the image every image_interval_s while a page takes images, a map
// snapshot every map_interval_s) into a small queue; its own thread serialises the JSON, encodes the JPEG, aligns the
// ground truth and publishes to the EventStream. The queue keeps at most a few items and drops the oldest,
// so a slow browser or encoder never slows tracking.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <variant>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/system/run_observer.h"
#include "crowdslam/system/system.h"
#include "crowdslam/viewer/event_stream.h"
#include "crowdslam/viewer/messages.h"
#include "crowdslam/viewer/run_control.h"

namespace crowdslam::viewer {

struct ViewerObserverOptions {
  double frame_interval_s = 0.1;
  double image_interval_s = 0.25;
  double map_interval_s = 1.0;
  int image_max_width = 640;
  size_t max_ground_truth_points = 3000;
  io::Trajectory ground_truth;  // empty: none
  bool monocular = false;       // ground truth aligned with scale (Sim3)
};

class ViewerObserver : public system::RunObserver {
 public:
  ViewerObserver(EventStream& stream, const RunControl* control, ViewerObserverOptions options);
  ~ViewerObserver() override;
  ViewerObserver(const ViewerObserver&) = delete;
  ViewerObserver& operator=(const ViewerObserver&) = delete;

  void on_frame(const system::FrameReport& report, const std::optional<geometry::SE3>& world_from_cam,
                const io::FrameImages& images) override;
  void on_keyframe(uint64_t id) override;
  void on_reset(const system::MapSegment& segment) override;
  [[nodiscard]] double map_snapshot_interval_s() const override { return options_.map_interval_s; }
  void on_map_snapshot(const std::shared_ptr<const system::MapSnapshot>& snapshot) override;
  void on_finish(const system::EndState& end) override;

  // Messages dropped because the queue was full (the browser side fell behind).
  [[nodiscard]] size_t dropped() const;
  // Waits until every queued item is published (tests), then stops the thread.
  void stop();

 private:
  struct ImageItem {
    size_t index;
    cv::Mat image;
    std::vector<people::PersonBox> boxes;
    std::vector<cv::KeyPoint> kept, removed;
  };
  struct EventItem {
    std::string event;
    std::string data;
    bool retain = true;  // replayed to pages that connect later (a map reset is not)
  };
  using Item = std::variant<FrameStatus, ImageItem, std::shared_ptr<const system::MapSnapshot>, EventItem>;
  void push(Item item);
  void run();
  void publish(Item& item);

  EventStream& stream_;
  const RunControl* control_;
  ViewerObserverOptions options_;
  // Tracking thread only.
  std::chrono::steady_clock::time_point last_frame_{}, last_image_{}, fps_start_{};
  size_t fps_frames_ = 0;
  double fps_ = 0;
  size_t keyframes_ = 0;
  // Shared with the worker.
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Item> queue_;
  std::vector<std::pair<double, geometry::Vec3>> estimate_;  // every tracked position (for the GT alignment)
  size_t dropped_ = 0;
  bool stopping_ = false;
  std::thread worker_;
};

}  // namespace crowdslam::viewer
