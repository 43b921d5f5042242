#include "crowdslam/system/system.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/map/keyframe.h"

namespace crowdslam::system {

namespace {
double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}
}  // namespace

geometry::PinholeCamera camera_from_settings(const io::Settings& settings, io::SensorKind sensor) {
  geometry::PinholeCamera camera;
  const auto& c = settings.camera;
  camera.fx = c.fx;
  camera.fy = c.fy;
  camera.cx = c.cx;
  camera.cy = c.cy;
  camera.distortion = {c.k1, c.k2, c.p1, c.p2, c.k3};
  camera.width = c.width;
  camera.height = c.height;
  camera.bf = sensor == io::SensorKind::kMonocular ? 0.0 : c.bf;
  return camera;
}

System::System(const io::Settings& settings, const SystemOptions& options)
    : settings_(settings), options_(options), map_(std::make_shared<map::Map>()) {
  camera_ = std::make_shared<geometry::PinholeCamera>(camera_from_settings(settings, options.sensor));

  tracking::FrameBuilder::Options builder_options;
  builder_options.orb.num_features = settings.orb.n_features;
  builder_options.orb.scale_factor = static_cast<float>(settings.orb.scale_factor);
  builder_options.orb.num_levels = settings.orb.n_levels;
  builder_options.orb.ini_th_fast = settings.orb.ini_th_fast;
  builder_options.orb.min_th_fast = settings.orb.min_th_fast;
  builder_options.depth_map_factor = settings.depth_map_factor > 0 ? settings.depth_map_factor : 1.0;
  frame_builder_ = std::make_unique<tracking::FrameBuilder>(camera_, builder_options);

  const double close_depth_m = camera_->bf > 0 ? settings.th_depth * camera_->bf / camera_->fx : 40.0;
  mapping::LocalMapperOptions mapper_options;
  mapper_options.monocular = options.sensor == io::SensorKind::kMonocular;
  mapper_options.close_depth_m = close_depth_m;
  mapper_ = std::make_unique<mapping::LocalMapper>(mapper_options, map_);

  tracking::TrackerOptions tracker_options;
  tracker_options.close_depth_m = close_depth_m;
  tracker_options.max_frames_between_keyframes = std::max(1, static_cast<int>(std::lround(settings.camera.fps)));
  tracker_ = std::make_unique<tracking::Tracker>(tracker_options, map_, mapper_.get());

  if (!options.sequential) mapper_->start();
}

System::~System() { shutdown(); }

void System::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  mapper_->stop();
}

FrameReport System::track(const io::FrameImages& images, double timestamp_s) {
  FrameReport report;
  report.index = next_frame_id_;
  report.timestamp_s = timestamp_s;

  const auto extraction_start = std::chrono::steady_clock::now();
  const cv::Mat gray = feature::to_gray(images.colour);
  tracking::RawFeatures raw;
  report.feature_budget = frame_builder_->default_num_features();
  frame_builder_->extract(gray, report.feature_budget, raw);
  const cv::Mat depth = options_.sensor == io::SensorKind::kRgbd ? images.depth : cv::Mat();
  auto features = frame_builder_->assemble(std::move(raw), depth);
  report.extraction_ms = elapsed_ms(extraction_start);
  report.keypoints = static_cast<int>(features->size());

  const auto tracking_start = std::chrono::steady_clock::now();
  map::Frame frame(next_frame_id_++, timestamp_s, camera_, frame_builder_->levels(), std::move(features));
  const tracking::TrackResult result = tracker_->track(std::move(frame));
  if (options_.sequential) mapper_->process_all();
  report.tracking_ms = elapsed_ms(tracking_start);

  report.state = result.state;
  report.method = result.method;
  report.new_keyframe = result.new_keyframe;
  report.tracked_points = result.tracked_points;

  TrajectoryRecord record;
  record.timestamp_s = timestamp_s;
  if (result.state == tracking::TrackingState::kOk && result.cam_from_world && result.reference_keyframe) {
    record.reference = result.reference_keyframe;
    record.cam_from_reference = *result.cam_from_world * result.reference_keyframe->world_from_cam();
    record.tracked = true;
  }
  records_.push_back(std::move(record));
  if (result.map_reset) reset_map();
  return report;
}

void System::reset_map() {
  ++map_resets_;
  const bool threaded = !options_.sequential;
  if (threaded) mapper_->stop();
  mapper_->reset();
  // Frames tracked against the discarded map live in another coordinate frame: drop them.
  for (auto& r : records_) {
    r.tracked = false;
    r.reference.reset();
  }
  map_->clear();
  tracker_->reset();
  if (threaded) mapper_->start();
}

io::Trajectory System::camera_trajectory() const {
  io::Trajectory trajectory;
  for (const auto& r : records_) {
    if (!r.tracked) continue;
    // A culled reference keyframe is replaced by its parent, accumulating the relative pose.
    geometry::SE3 cam_from_keyframe = r.cam_from_reference;
    std::shared_ptr<map::KeyFrame> keyframe = r.reference;
    int guard = 0;
    while (keyframe && keyframe->is_bad() && guard++ < 100000) {
      cam_from_keyframe = cam_from_keyframe * keyframe->cam_from_parent_at_erase();
      keyframe = keyframe->parent();
    }
    if (!keyframe) continue;
    const geometry::SE3 cam_from_world = cam_from_keyframe * keyframe->cam_from_world();
    trajectory.push_back({r.timestamp_s, cam_from_world.inverse()});
  }
  return trajectory;
}

io::Trajectory System::keyframe_trajectory() const {
  io::Trajectory trajectory;
  for (const auto& kf : map_->keyframes()) {
    if (kf->is_bad()) continue;
    trajectory.push_back({kf->timestamp_s, kf->world_from_cam()});
  }
  return trajectory;
}

size_t System::num_keyframes() const { return map_->num_keyframes(); }
size_t System::num_map_points() const { return map_->num_map_points(); }
mapping::LocalMapperStats System::mapper_stats() const { return mapper_->stats(); }

}  // namespace crowdslam::system
