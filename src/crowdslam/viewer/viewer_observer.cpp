#include "crowdslam/viewer/viewer_observer.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "crowdslam/util/thread_priority.h"

namespace crowdslam::viewer {

namespace {
constexpr size_t kQueueLimit = 8;
double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

ViewerObserver::ViewerObserver(EventStream& stream, const RunControl* control, ViewerObserverOptions options)
    : stream_(stream), control_(control), options_(std::move(options)) {
  fps_start_ = std::chrono::steady_clock::now();
  worker_ = std::thread([this] {
    util::set_thread_name("cs-viewer");
    run();
  });
}

ViewerObserver::~ViewerObserver() { stop(); }

void ViewerObserver::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && !worker_.joinable()) return;
    stopping_ = true;
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

size_t ViewerObserver::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

void ViewerObserver::push(Item item) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    // Full: drop the oldest image or status first (map snapshots and events are rarer and matter more).
    if (queue_.size() >= kQueueLimit) {
      for (auto it = queue_.begin(); it != queue_.end(); ++it) {
        if (std::holds_alternative<ImageItem>(*it) || std::holds_alternative<FrameStatus>(*it)) {
          queue_.erase(it);
          ++dropped_;
          break;
        }
      }
    }
    queue_.push_back(std::move(item));
  }
  cv_.notify_one();
}

void ViewerObserver::on_frame(const system::FrameReport& report, const std::optional<geometry::SE3>& world_from_cam,
                              const io::FrameImages& images) {
  ++fps_frames_;
  const double window = seconds_since(fps_start_);
  if (window >= 1.0) {
    fps_ = static_cast<double>(fps_frames_) / window;
    fps_frames_ = 0;
    fps_start_ = std::chrono::steady_clock::now();
  }
  if (world_from_cam) {
    std::lock_guard lock(mutex_);
    estimate_.emplace_back(report.timestamp_s, world_from_cam->translation());
  }
  const auto now = std::chrono::steady_clock::now();
  const bool paused = control_ && control_->paused();
  if (paused || std::chrono::duration<double>(now - last_frame_).count() >= options_.frame_interval_s) {
    last_frame_ = now;
    FrameStatus s;
    s.index = report.index;
    s.timestamp_s = report.timestamp_s;
    s.state = tracking::to_string(report.state);
    s.method = report.method;
    s.world_from_cam = world_from_cam;
    s.fps = fps_;
    s.tracking_ms = report.tracking_ms;
    s.keypoints = report.keypoints;
    s.tracked_points = report.tracked_points;
    s.person_boxes = report.person_boxes;
    s.people_area = report.people_area;
    s.feature_budget = report.feature_budget;
    s.keyframes = keyframes_;
    s.paused = paused;
    push(std::move(s));
  }
  // Images only for a page that shows them (encoding one costs the SLAM machine's CPU too).
  if (!images.colour.empty() &&
      (paused || std::chrono::duration<double>(now - last_image_).count() >= options_.image_interval_s) &&
      stream_.taken("image")) {
    last_image_ = now;
    push(ImageItem{report.index, images.colour.clone(), report.boxes, report.kept_keypoints, report.removed_keypoints});
  }
}

void ViewerObserver::on_keyframe(uint64_t /*id*/) { ++keyframes_; }

void ViewerObserver::on_reset(const system::MapSegment& segment) {
  {
    std::lock_guard lock(mutex_);
    estimate_.clear();
  }
  push(EventItem{"reset", nlohmann::json({{"map_id", segment.map_id}, {"last_frame", segment.last_frame}}).dump(),
                 false});
}

void ViewerObserver::on_map_snapshot(const std::shared_ptr<const system::MapSnapshot>& snapshot) { push(snapshot); }

void ViewerObserver::on_finish(const system::EndState& end) {
  push(EventItem{"finish", nlohmann::json({{"end_state", end.to_string()}}).dump()});
}

void ViewerObserver::run() {
  while (true) {
    Item item;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopping and drained
      item = std::move(queue_.front());
      queue_.pop_front();
    }
    try {
      publish(item);
    } catch (const std::exception& e) {
      spdlog::warn("viewer: {}", e.what());
    }
  }
}

void ViewerObserver::publish(Item& item) {
  if (auto* status = std::get_if<FrameStatus>(&item)) {
    stream_.publish("frame", frame_json(*status));
  } else if (auto* image = std::get_if<ImageItem>(&item)) {
    // No wider than the widest page shows it (a small panel needs a quarter of the pixels).
    const int wanted = stream_.image_width();
    const int width = wanted > 0 ? std::min(wanted, options_.image_max_width) : options_.image_max_width;
    stream_.publish("image", image_json(image->index, image->image, image->boxes, image->kept, image->removed, width));
  } else if (auto* snapshot = std::get_if<std::shared_ptr<const system::MapSnapshot>>(&item)) {
    stream_.publish("map", map_json(**snapshot));
    if (!options_.ground_truth.empty()) {
      std::vector<std::pair<double, geometry::Vec3>> estimate;
      {
        std::lock_guard lock(mutex_);
        estimate = estimate_;
      }
      if (const auto alignment = align_ground_truth(options_.ground_truth, estimate, options_.monocular)) {
        stream_.publish("ground_truth",
                        ground_truth_json(options_.ground_truth, *alignment, options_.max_ground_truth_points));
      }
    }
  } else if (auto* event = std::get_if<EventItem>(&item)) {
    stream_.publish(event->event, event->data, event->retain);
  }
}

}  // namespace crowdslam::viewer
