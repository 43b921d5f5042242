#include "crowdslam/system/system.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>

#include "crowdslam/bow/vocabulary_path.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/util/error.h"

namespace crowdslam::system {

namespace {
// Iterations of the global BA with the ground that ends a completed run (20: converged on kitti07_head
// and its variants, docs/MAPPING.md "Ground constraint").
constexpr int kFinalGroundBaIterations = 20;

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
  load_vocabulary();
  // Frames get their bag of words from tracking, only when needed (tracking/frame_bow.h).
  frame_builder_ = std::make_unique<tracking::FrameBuilder>(camera_, builder_options);
  if (options.sensor == io::SensorKind::kStereo && settings.rectification) {
    rectifier_ = std::make_unique<geometry::StereoRectifier>(*settings.rectification, settings.path);
  }

  if (options.sensor == io::SensorKind::kMonocular && settings.ground.enabled) {
    geometry::GroundPlaneOptions ground;
    ground.keyframe_sigma = settings.ground.keyframe_sigma;
    ground_ = ground;
  }

  const double close_depth_m = camera_->bf > 0 ? settings.th_depth * camera_->bf / camera_->fx : 40.0;
  mapping::LocalMapperOptions mapper_options;
  mapper_options.monocular = options.sensor == io::SensorKind::kMonocular;
  mapper_options.close_depth_m = close_depth_m;
  mapper_options.delay_ms = options.mapper_delay_ms;
  mapper_options.thread_nice = options.background_nice;
  // Part of keeping people out, as the feature budget: the static-world baseline (--no-people-filter) runs
  // without it, as ORB-SLAM. There tracking follows whatever moves, and its relative poses would only pass
  // that on (docs/CROWDS.md#keyframes-that-see-a-strip-of-background).
  mapper_options.odometry_sigma_deg =
      options.people_filter && settings.people_filter.enabled ? settings.tracking.odometry_sigma_deg : 0.0;
  mapper_ = std::make_unique<mapping::LocalMapper>(mapper_options, map_);

  tracking::TrackerOptions tracker_options;
  tracker_options.close_depth_m = close_depth_m;
  const std::string& in_boxes = settings.people_filter.static_in_boxes;
  const bool mono = options.sensor == io::SensorKind::kMonocular;
  tracker_options.box_keypoints = in_boxes == "always" || in_boxes == "auto" || (in_boxes == "monocular" && mono);
  tracker_options.box_check_below = settings.people_filter.static_check_below;
  if (in_boxes == "auto" && !mono) {
    // With depth, only a frame the filtered keypoints fail on, near the motion model's pose, and nothing
    // of it mapped (docs/CROWDS.md#box-keypoints-taken-back-by-the-static-map).
    tracker_options.box_check_below = 0;
    tracker_options.box_release = false;
    tracker_options.box_rescue_keyframes = false;
    tracker_options.box_rescue_gate_m = 0.05;
    tracker_options.box_rescue_gate_deg = 1.5;
    tracker_options.box_rescue_after_bridge_s = 1.0;
  }
  tracker_options.box_rescue = true;
  tracker_options.max_wait_for_mapping_ms = options.sequential ? 0.0 : options.max_wait_for_mapping_ms;
  tracker_options.monocular_replay_waits = options.replay_waits_for_mapping;
  tracker_options.max_frames_between_keyframes = std::max(1, static_cast<int>(std::lround(settings.camera.fps)));
  if (options.sensor == io::SensorKind::kMonocular) {
    tracker_options.monocular = true;
    tracker_options.local_map_radius_factor = 1.0;  // ORB-SLAM2's window for monocular local-map tracking
    // Monocular boxes hide the background behind a person too (no depth to keep it), so more of their
    // keypoints are static: a pose from box keypoints needs the ordinary 30 inliers, not 50 (measured on
    // bonn_crowd: 98.9 % against 97.1 % tracked).
    tracker_options.box_rescue_min_inliers = 30;
  }
  if (options.sensor == io::SensorKind::kStereo) {
    // ORB-SLAM2 starts a stereo map from a frame with 500 keypoints; about half of them find a stereo
    // partner (measured on EuRoC and the synthetic sequences), so ask for that many points with depth.
    tracker_options.min_init_features = 250;
  }
  tracker_options.odometry_bridge_min_inliers = settings.tracking.odometry_bridge_min_inliers;
  tracker_options.bridge_max_s = settings.tracking.bridge_max_s;
  tracker_options.reanchor_max_s = settings.tracking.reanchor_max_s;
  tracker_options.keyframe_reference_ratio = settings.tracking.keyframe_reference_ratio;
  tracker_options.bridge_min_people_share = settings.tracking.bridge_min_people_share;
  const io::GeometrySettings& g = settings.geometry;
  tracker_options.dynamic.enabled = g.dynamic_check;
  tracker_options.dynamic.moving_factor = g.moving_factor;
  tracker_options.dynamic.certain_factor = g.certain_factor;
  tracker_options.dynamic.dynamic_score = g.dynamic_score;
  tracker_options.dynamic.cull_score = g.cull_score;
  tracker_options.dynamic.region_radius_px = g.region_radius_px;
  tracker_options.dynamic.region_depth_m = g.region_depth_m;
  tracker_options.dynamic.region_depth_ratio = g.region_depth_ratio;
  tracker_options.dynamic.region_steps = g.region_steps;
  tracker_options.dynamic.free_space_margin_m = g.free_space_margin_m;
  tracker_options.dynamic.free_space_ratio = g.free_space_ratio;
  tracker_options.dynamic.free_space_cull_run = g.free_space_cull_run;
  box_keypoints_ = tracker_options.box_keypoints;
  tracker_ = std::make_unique<tracking::Tracker>(tracker_options, map_, mapper_.get());
  if (vocabulary_) {
    keyframe_database_ = std::make_unique<loop::KeyframeDatabase>();
    mapper_->set_keyframe_database(keyframe_database_.get());
    tracker_->set_keyframe_database(keyframe_database_.get());
    tracker_->set_vocabulary(vocabulary_);
    if (options.loop_closing) {
      loop::LoopCloserOptions loop_options;
      loop_options.fix_scale = options.sensor != io::SensorKind::kMonocular;
      loop_options.ground = ground_;
      loop_options.thread_nice = options.background_nice;
      loop_closer_ = std::make_unique<loop::LoopCloser>(loop_options, map_, keyframe_database_.get(), mapper_.get());
      mapper_->set_keyframe_done(
          [closer = loop_closer_.get()](const std::shared_ptr<map::KeyFrame>& keyframe) { closer->insert_keyframe(keyframe); });
      if (!options.sequential) loop_closer_->start();
    }
  }

  next_feature_budget_ = frame_builder_->default_num_features();
  if (options.people_filter && settings.people_filter.enabled) {
    people::PeopleStageOptions people_options;
    people_options.sensor = options.sensor;
    people_options.detections_file = options.detections_file;
    people_options.detector_model = options.detector_model;
    people_ = std::make_unique<people::PeopleStage>(settings, people_options);
  }
  if (!options.sequential) mapper_->start();
}

void System::load_vocabulary() {
  if (options_.vocabulary_path == "none") {
    spdlog::info("no vocabulary: relocalisation by brute-force matching, no place recognition");
    return;
  }
  const std::string path =
      options_.vocabulary_path.empty() ? bow::default_vocabulary_path() : options_.vocabulary_path;
  const auto start = std::chrono::steady_clock::now();
  try {
    vocabulary_ = std::make_shared<const bow::Vocabulary>(bow::Vocabulary::read(path));
  } catch (const InputError& e) {
    if (!options_.vocabulary_path.empty()) throw;
    throw InputError(std::string(e.what()) +
                     " (default vocabulary: build it with scripts/build_vocabulary.sh, point CROWDSLAM_VOCABULARY "
                     "at one, or run with --vocabulary none)");
  }
  if (vocabulary_->empty()) throw input_error(path, "empty vocabulary");
  vocabulary_info_ = VocabularyInfo{path, vocabulary_->num_words(), elapsed_ms(start)};
  spdlog::info("vocabulary {}: {} words (k {}, L {}), loaded in {:.1f} ms", path, vocabulary_info_->words,
               vocabulary_->k(), vocabulary_->levels(), vocabulary_info_->load_ms);
}

std::string System::detector_name() const { return people_ ? people_->detector_name() : std::string("none"); }

System::~System() { shutdown(); }

void System::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  mapper_->stop();
  if (loop_closer_) loop_closer_->stop();  // after the mapper: it may still hand over keyframes
  erase_culled_points();
  if (ground_ && !localization_only()) {  // a map only localised in is left as it was loaded
    // All threads have stopped: the map is final but for this adjustment. Frames follow their keyframes.
    loop::GlobalBundleAdjuster adjuster(map_, nullptr, kFinalGroundBaIterations);
    adjuster.set_ground(*ground_);
    FinalGroundBa result;
    result.keyframes = static_cast<int>(map_->num_keyframes());
    result.applied = adjuster.run();
    result.stats = adjuster.stats();
    final_ground_ba_ = result;
  }
}

void System::stop_now() {
  if (shut_down_) return;
  shut_down_ = true;
  mapper_->stop_now();
  if (loop_closer_) loop_closer_->stop_now();
  erase_culled_points();
}

void System::erase_culled_points() {
  // Points tracking culled after the mapper's last pass (the dynamic check) leave the map too, so that
  // its count, its snapshot and a saved map agree. A map only localised in is left as it was loaded.
  if (!localization_only()) map_->erase_bad_map_points();
}

void System::finish(const EndState& end) {
  if (end.completed()) {
    shutdown();
  } else {
    stop_now();
  }
  publish_map_snapshot(true);
  for (auto* observer : observers_) observer->on_finish(end);
}

std::string EndState::to_string() const {
  switch (kind) {
    case Kind::kCompleted:
      return "completed";
    case Kind::kInterrupted:
      return "interrupted";
    case Kind::kFailed:
      return "failed: " + reason;
  }
  return "failed: " + reason;
}

std::shared_ptr<const PreparedFrame> System::prepare(const io::FrameImages& images) {
  // Monocular frames are not prepared: a threaded monocular replay then lost kitti07_head (every 4th frame)
  // at its start in 4 of 40 runs, against 0 of 40 without (the same computations, other timing).
  if (options_.sensor == io::SensorKind::kMonocular) return nullptr;
  if (rectifier_ || images.colour.empty()) return nullptr;
  if (!preparer_) preparer_ = std::make_unique<feature::ORBExtractor>(frame_builder_->orb_options());
  auto prepared = std::make_shared<PreparedFrame>();
  try {
    preparer_->prepare(feature::to_gray(images.colour), prepared->orb);
  } catch (const InputError&) {
    return nullptr;  // track() reports it, in the frame's turn
  }
  if (options_.prepare_detection && people_ && people_->detects_ahead()) {
    prepared->detection_ticket = people_->submit_ahead(prepared_frames_, images.colour);
  }
  ++prepared_frames_;
  return prepared;
}

FrameReport System::track(const io::FrameImages& images, double timestamp_s) {
  return track(images, timestamp_s, nullptr);
}

FrameReport System::track(const io::FrameImages& images, double timestamp_s, const PreparedFrame* prepared) {
  FrameReport report;
  report.index = next_frame_id_;
  report.timestamp_s = timestamp_s;

  const size_t frame_index = next_frame_id_;
  const bool stereo = options_.sensor == io::SensorKind::kStereo;
  if (stereo && images.right.empty()) {
    throw InputError("frame " + std::to_string(frame_index) + ": stereo needs a right image");
  }
  report.feature_budget = next_feature_budget_;
  // Monocular initialisation extracts twice the features (ORB-SLAM2), for enough two-view matches.
  if (options_.sensor == io::SensorKind::kMonocular &&
      tracker_->state() == tracking::TrackingState::kNotInitialized) {
    report.feature_budget *= 2;
  }
  const auto extraction_start = std::chrono::steady_clock::now();
  // Stereo: both images are rectified here first, then the right image's ORB is extracted on a second
  // thread while the left one is extracted here. (cv::remap uses OpenCV's thread pool; called while the
  // other thread's ORB also uses it, the left remap waited for that: 55 instead of 95 frames/s measured
  // on euroc_v101_micro without the people filter.) Declared before the future, whose destructor waits
  // for the thread, so they outlive it even on an exception.
  cv::Mat left_colour = images.colour;
  cv::Mat right_gray;
  feature::RawFeatures raw_right;
  std::future<void> right_done;
  if (stereo) {
    right_gray = feature::to_gray(images.right);
    if (rectifier_) {
      rectifier_->rectify_left(images.colour, left_colour);
      cv::Mat rectified;
      rectifier_->rectify_right(right_gray, rectified);
      right_gray = rectified;
    }
    right_done = std::async(std::launch::async, [this, &right_gray, &raw_right, budget = report.feature_budget] {
      frame_builder_->extract_right(right_gray, budget, raw_right);
    });
  }
  // The detector works on its own thread while ORB features are extracted here.
  if (rectifier_) prepared = nullptr;  // prepared from the unrectified image
  const cv::Mat gray = prepared ? prepared->orb.gray : feature::to_gray(left_colour);
  if (people_) {
    people_->begin_frame(frame_index, left_colour, gray,
                         prepared ? prepared->detection_ticket : std::nullopt);
  }
  feature::RawFeatures raw;
  if (prepared) {
    frame_builder_->extract(prepared->orb, report.feature_budget, raw);
  } else {
    frame_builder_->extract(gray, report.feature_budget, raw);
  }
  report.keypoints_before_filter = static_cast<int>(raw.keys.size());
  if (stereo) {
    // Matched before the people filter, whose depth mode needs the keypoints' depths.
    const auto wait_start = std::chrono::steady_clock::now();
    right_done.get();
    report.right_wait_ms = elapsed_ms(wait_start);
    const auto match_start = std::chrono::steady_clock::now();
    frame_builder_->match_stereo(raw, raw_right);
    report.stereo_match_ms = elapsed_ms(match_start);
  }
  // The keypoints before the filter: tracking may take back those in boxes (Tracker::track).
  std::optional<feature::RawFeatures> unfiltered;
  std::vector<long> filtered_index;
  std::vector<int> box_of;
  if (people_) {
    if (box_keypoints_) {
      unfiltered.emplace(feature::RawFeatures{raw.keys, raw.descriptors.clone(), raw.right_u, raw.depth_m});
    }
    people::PeopleFrame p = people_->filter(frame_index, images, raw, options_.record_keypoints);
    report.person_boxes = p.person_boxes;
    report.people_area = p.people_area;
    report.keypoints_before_filter = p.keypoints_before_filter;
    report.detector_ms = p.detector_ms;
    report.detector_wait_ms = p.detector_wait_ms;
    report.right_keypoints_removed = p.right_keypoints_removed;
    report.flat_boxes = p.flat_boxes;
    report.detection_frame = p.detection_frame;
    report.boxes_propagated = p.boxes_propagated;
    report.boxes = std::move(p.boxes);
    report.removed_keypoints = std::move(p.removed_keypoints);
    next_feature_budget_ = people_->next_feature_budget();
    filtered_index = std::move(p.filtered_index);
    box_of = std::move(p.box_of);
    if (unfiltered && unfiltered->keys.size() == raw.keys.size()) unfiltered.reset();  // nothing was removed
  }
  if (options_.record_keypoints) report.kept_keypoints = raw.keys;
  std::shared_ptr<map::FrameFeatures> features;
  if (stereo) {
    report.stereo_matches = static_cast<int>(std::count_if(raw.depth_m.begin(), raw.depth_m.end(), [](float d) { return d > 0; }));
    features = frame_builder_->assemble_stereo(std::move(raw));
  } else {
    const cv::Mat depth = options_.sensor == io::SensorKind::kRgbd ? images.depth : cv::Mat();
    features = frame_builder_->assemble(std::move(raw), depth);
  }
  // Extraction time excludes the wait for the detector (reported on its own).
  report.extraction_ms = elapsed_ms(extraction_start) - report.detector_wait_ms;
  report.keypoints = static_cast<int>(features->size());

  const auto tracking_start = std::chrono::steady_clock::now();
  map::Frame frame(next_frame_id_++, timestamp_s, camera_, frame_builder_->levels(), std::move(features));
  if (options_.sensor == io::SensorKind::kRgbd) {
    frame.depth_raw = images.depth;
    frame.depth_metres_per_unit = 1.0 / frame_builder_->depth_map_factor();
  }
  tracking::Tracker::BoxKeypoints box_keypoints;
  if (unfiltered && filtered_index.size() == unfiltered->keys.size()) {
    box_keypoints.filtered_index = std::move(filtered_index);
    box_keypoints.box_of = std::move(box_of);
    // Built on the first call only (tracking may ask twice: for the pose, then for relocalisation).
    box_keypoints.features = [&, built = std::shared_ptr<const map::FrameFeatures>()]() mutable {
      if (!built) {
        const cv::Mat depth = options_.sensor == io::SensorKind::kRgbd ? images.depth : cv::Mat();
        built = stereo ? frame_builder_->assemble_stereo(std::move(*unfiltered))
                       : frame_builder_->assemble(std::move(*unfiltered), depth);
      }
      return built;
    };
  }
  const double people_share =
      report.keypoints_before_filter > 0
          ? 1.0 - static_cast<double>(report.keypoints) / static_cast<double>(report.keypoints_before_filter)
          : 0.0;
  const tracking::TrackResult result = tracker_->track(std::move(frame), box_keypoints, people_share);
  if (options_.sequential) {
    mapper_->process_all();
    if (loop_closer_) loop_closer_->process_all();
  }
  report.tracking_ms = elapsed_ms(tracking_start);

  report.state = result.state;
  report.method = result.method;
  if (report.method == "reanchor") ++reanchors_;
  report.new_keyframe = result.new_keyframe;
  report.rescued_with_boxes = result.rescued_with_boxes;
  report.box_matches = result.box_matches;
  report.static_boxes = result.static_boxes;
  report.waited_for_mapping_ms = result.waited_for_mapping_ms;
  report.keypoints_dynamic = result.dynamic.dynamic;
  report.dynamic_grown = result.dynamic.grown;
  report.matches_moving = result.dynamic.moving;
  report.points_culled_moving = result.dynamic.points_culled;
  report.points_seen_through = result.dynamic.free_space;
  report.dynamic_check_skipped = result.dynamic.skipped;
  report.tracked_points = result.tracked_points;

  TrajectoryRecord record;
  record.timestamp_s = timestamp_s;
  record.segment = map_resets_;
  std::optional<geometry::SE3> world_from_cam;
  if (result.state == tracking::TrackingState::kOk && result.cam_from_world && result.reference_keyframe) {
    record.reference = result.reference_keyframe;
    record.cam_from_reference = *result.cam_from_world * result.reference_keyframe->world_from_cam();
    record.world_from_cam = result.cam_from_world->inverse();
    record.tracked = true;
    world_from_cam = record.world_from_cam;
  } else if (result.state == tracking::TrackingState::kBridged && result.bridged_cam_from_world &&
             result.reference_keyframe) {
    // Not tracked: the motion model's pose while people hide the view (bridged_trajectory()).
    record.reference = result.reference_keyframe;
    record.cam_from_reference = *result.bridged_cam_from_world * result.reference_keyframe->world_from_cam();
    record.world_from_cam = result.bridged_cam_from_world->inverse();
    record.bridged = true;
  }
  if (segments_.empty()) segments_.push_back(MapSegment{0, report.index, report.index, 0, 0, 0, 0, 0});
  MapSegment& segment = segments_.back();
  segment.last_frame = report.index;
  ++segment.frames;
  if (record.tracked) {
    if (segment.tracked++ == 0) segment.first_stamp_s = timestamp_s;
    segment.last_stamp_s = timestamp_s;
  }
  records_.push_back(std::move(record));
  // Monocular initialisation makes its reference frame (an earlier frame, reported not initialised then)
  // the first keyframe: that frame's pose is the keyframe's, so it is tracked too. Earlier frames the map
  // localises come with the initialising frame or, tried again once the map has grown, with a later one;
  // frames lost before a monocular re-anchoring come with the re-anchoring frame (its reference frame
  // listed among them).
  const bool init = result.method == std::string("init");
  const auto& first = result.recovered_reference;
  if (options_.sensor == io::SensorKind::kMonocular && first && first->frame_id < records_.size()) {
    const bool reanchored = result.method == std::string("reanchor");
    auto recovered = result.recovered;
    if (init) recovered.emplace_back(first->frame_id, first->cam_from_world());
    for (const auto& [frame_id, cam_from_world] : recovered) {
      if (frame_id >= records_.size()) continue;
      TrajectoryRecord& earlier = records_[frame_id];
      if (earlier.tracked || earlier.segment != map_resets_) continue;
      earlier.tracked = true;
      earlier.bridged = false;
      earlier.reference = first;
      earlier.cam_from_reference = cam_from_world * first->world_from_cam();
      earlier.world_from_cam = cam_from_world.inverse();
      MapSegment& current = segments_.back();
      if (current.tracked++ == 0 || earlier.timestamp_s < current.first_stamp_s) current.first_stamp_s = earlier.timestamp_s;
      if (earlier.timestamp_s > current.last_stamp_s) current.last_stamp_s = earlier.timestamp_s;
      (reanchored ? report.localized_after_reanchor : report.localized_before_init).push_back(frame_id);
    }
  }
  for (auto* observer : observers_) observer->on_frame(report, world_from_cam, images);
  if (result.new_keyframe && result.reference_keyframe) {  // a new keyframe becomes the reference
    for (auto* observer : observers_) observer->on_keyframe(result.reference_keyframe->id);
  }
  if (result.map_reset) reset_map();
  publish_map_snapshot(false);
  return report;
}

void System::reset_map() {
  ++map_resets_;
  const bool threaded = !options_.sequential;
  if (threaded) mapper_->stop();
  if (loop_closer_) {
    if (threaded) loop_closer_->stop();
    loop_closer_->reset();
  }
  mapper_->reset();
  // Frames tracked against the discarded map keep the poses that map gave them (its own coordinate
  // frame, listed as a segment); only the links into the map are cut.
  for (auto& r : records_) {
    if (!r.reference) continue;
    r.world_from_cam = world_from_cam(r);
    r.reference.reset();
  }
  const io::Trajectory keyframes = live_keyframe_trajectory();
  past_keyframes_.insert(past_keyframes_.end(), keyframes.begin(), keyframes.end());
  MapSegment ended = segments_.back();
  ended.keyframes = keyframes.size();
  segments_.back() = ended;
  segments_.push_back(MapSegment{map_resets_, next_frame_id_, next_frame_id_, 0, 0, 0, 0, 0});
  segments_.back().frames = 0;
  for (auto* observer : observers_) observer->on_reset(ended);
  if (keyframe_database_) keyframe_database_->clear();
  map_->clear();
  tracker_->reset();
  if (threaded) mapper_->start();
  if (threaded && loop_closer_) loop_closer_->start();
}

geometry::SE3 System::world_from_cam(const TrajectoryRecord& r) const {
  if (!r.reference) return r.world_from_cam;
  // A culled reference keyframe is replaced by its parent, accumulating the relative pose.
  geometry::SE3 cam_from_keyframe = r.cam_from_reference;
  std::shared_ptr<map::KeyFrame> keyframe = r.reference;
  int guard = 0;
  while (keyframe && keyframe->is_bad() && guard++ < 100000) {
    cam_from_keyframe = cam_from_keyframe * keyframe->cam_from_parent_at_erase();
    keyframe = keyframe->parent();
  }
  if (!keyframe) return r.world_from_cam;  // no surviving ancestor: the pose tracking gave it
  return (cam_from_keyframe * keyframe->cam_from_world()).inverse();
}

std::vector<io::Trajectory> System::camera_trajectory_segments() const {
  std::vector<io::Trajectory> trajectories(std::max<size_t>(1, segments_.size()));
  for (const auto& r : records_) {
    if (!r.tracked) continue;
    trajectories[static_cast<size_t>(r.segment)].push_back({r.timestamp_s, world_from_cam(r)});
  }
  return trajectories;
}

io::Trajectory System::camera_trajectory() const {
  io::Trajectory trajectory;
  for (const auto& r : records_) {
    if (r.tracked) trajectory.push_back({r.timestamp_s, world_from_cam(r)});
  }
  return trajectory;
}

io::Trajectory System::bridged_trajectory() const {
  io::Trajectory trajectory;
  for (const auto& r : records_) {
    if (r.bridged) trajectory.push_back({r.timestamp_s, world_from_cam(r)});
  }
  return trajectory;
}

std::vector<io::Trajectory> System::bridged_trajectory_segments() const {
  std::vector<io::Trajectory> trajectories(std::max<size_t>(1, segments_.size()));
  for (const auto& r : records_) {
    if (r.bridged) trajectories[static_cast<size_t>(r.segment)].push_back({r.timestamp_s, world_from_cam(r)});
  }
  return trajectories;
}

size_t System::tracked_frames() const {
  return static_cast<size_t>(std::count_if(records_.begin(), records_.end(), [](const auto& r) { return r.tracked; }));
}

std::vector<MapSegment> System::segments() const {
  std::vector<MapSegment> result = segments_;
  if (!result.empty()) result.back().keyframes = live_keyframe_trajectory().size();
  return result;
}

io::Trajectory System::live_keyframe_trajectory() const {
  io::Trajectory trajectory;
  for (const auto& kf : map_->keyframes()) {
    if (kf->is_bad()) continue;
    trajectory.push_back({kf->timestamp_s, kf->world_from_cam()});
  }
  return trajectory;
}

io::Trajectory System::keyframe_trajectory() const {
  io::Trajectory trajectory = past_keyframes_;
  const io::Trajectory live = live_keyframe_trajectory();
  trajectory.insert(trajectory.end(), live.begin(), live.end());
  return trajectory;
}

size_t System::num_keyframes() const { return map_->num_keyframes(); }
size_t System::num_map_points() const { return map_->num_map_points(); }
mapping::LocalMapperStats System::mapper_stats() const { return mapper_->stats(); }

loop::LoopCloserStats System::loop_stats() const { return loop_closer_ ? loop_closer_->stats() : loop::LoopCloserStats{}; }

}  // namespace crowdslam::system
