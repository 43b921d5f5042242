#include "crowdslam/tracking/monocular_initializer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <unordered_map>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/match/rotation_histogram.h"
#include "crowdslam/optim/bundle_adjustment.h"
#include "crowdslam/util/error.h"

namespace crowdslam::tracking {

void MonocularInitializerOptions::check() const {
  if (min_keypoints < 8) throw InputError("monocular initializer: min_keypoints must be >= 8");
  if (min_matches < 8) throw InputError("monocular initializer: min_matches must be >= 8");
  if (!(window_px > 0)) throw InputError("monocular initializer: window_px must be > 0");
  if (!(nn_ratio > 0 && nn_ratio <= 1)) throw InputError("monocular initializer: nn_ratio must be in (0, 1]");
  if (max_level < 0) throw InputError("monocular initializer: max_level must be >= 0");
  if (min_map_points < 1) throw InputError("monocular initializer: min_map_points must be >= 1");
  if (ba_iterations < 1) throw InputError("monocular initializer: ba_iterations must be >= 1");
  two_view.check();
}

MonocularInitializer::MonocularInitializer(const MonocularInitializerOptions& options) : options_(options) {
  options_.check();
}

void MonocularInitializer::reset() {
  reference_.reset();
  previous_positions_.clear();
  last_num_matches_ = 0;
}

void MonocularInitializer::set_reference(const map::Frame& frame) {
  reference_ =
      std::make_shared<map::Frame>(frame.id, frame.timestamp_s, frame.camera, frame.levels, frame.features);
  previous_positions_.resize(frame.size());
  for (size_t i = 0; i < frame.size(); ++i) previous_positions_[i] = frame.features->keys_un[i].pt;
}

std::vector<std::pair<size_t, size_t>> MonocularInitializer::match(const map::Frame& frame) {
  const map::FrameFeatures& rf = *reference_->features;
  const map::FrameFeatures& cf = *frame.features;
  // Best reference keypoint per current keypoint: (reference index, distance).
  std::unordered_map<size_t, std::pair<size_t, int>> best_for_current;
  for (size_t i = 0; i < rf.size(); ++i) {
    const cv::KeyPoint& kp = rf.keys_un[i];
    if (kp.octave > options_.max_level) continue;
    const cv::Point2f& around = previous_positions_[i];
    const auto candidates = cf.grid.features_in_area(
        cf.keys_un, around.x, around.y, static_cast<float>(options_.window_px), kp.octave, kp.octave);
    int best = 256;
    int second = 256;
    size_t best_index = 0;
    for (size_t j : candidates) {
      const int d = feature::hamming_distance(rf.descriptor(i), cf.descriptor(j));
      if (d < best) {
        second = best;
        best = d;
        best_index = j;
      } else if (d < second) {
        second = d;
      }
    }
    if (best > match::kThLow || best >= options_.nn_ratio * second) continue;
    auto [it, inserted] = best_for_current.try_emplace(best_index, i, best);
    if (!inserted && best < it->second.second) it->second = {i, best};
  }
  std::vector<std::pair<size_t, size_t>> matches;
  matches.reserve(best_for_current.size());
  match::RotationHistogram histogram;
  for (const auto& [j, entry] : best_for_current) {
    histogram.add(rf.keys_un[entry.first].angle - cf.keys_un[j].angle, matches.size());
    matches.emplace_back(entry.first, j);
  }
  std::vector<bool> rejected(matches.size(), false);
  for (size_t k : histogram.rejected()) rejected[k] = true;
  std::vector<std::pair<size_t, size_t>> kept;
  kept.reserve(matches.size());
  for (size_t k = 0; k < matches.size(); ++k) {
    if (rejected[k]) continue;
    kept.push_back(matches[k]);
    previous_positions_[matches[k].first] = cf.keys_un[matches[k].second].pt;
  }
  // Deterministic order (the hash map's is not): by reference index.
  std::sort(kept.begin(), kept.end());
  return kept;
}

std::optional<TwoViewInitialization> MonocularInitializer::add_frame(const map::Frame& frame) {
  last_num_matches_ = 0;
  const bool enough_keypoints = frame.size() > static_cast<size_t>(options_.min_keypoints);
  if (!reference_) {
    if (enough_keypoints) set_reference(frame);
    return std::nullopt;
  }
  if (!enough_keypoints) {
    reset();
    return std::nullopt;
  }
  const auto matches = match(frame);
  last_num_matches_ = static_cast<int>(matches.size());
  if (last_num_matches_ < options_.min_matches) {
    spdlog::debug("monocular init: {} matches with reference frame {}: frame {} becomes the reference",
                  last_num_matches_, reference_->id, frame.id);
    set_reference(frame);
    return std::nullopt;
  }
  std::vector<geometry::Vec2> points1;
  std::vector<geometry::Vec2> points2;
  points1.reserve(matches.size());
  points2.reserve(matches.size());
  for (const auto& [i, j] : matches) {
    points1.emplace_back(reference_->features->keys_un[i].pt.x, reference_->features->keys_un[i].pt.y);
    points2.emplace_back(frame.features->keys_un[j].pt.x, frame.features->keys_un[j].pt.y);
  }
  geometry::TwoViewModels models;
  std::optional<geometry::TwoViewPrior> prior;
  if (prior_) prior = prior_(reference_->timestamp_s, frame.timestamp_s);
  const auto reconstruction = geometry::reconstruct_two_view(*frame.camera, points1, points2, options_.two_view,
                                                             &models, prior ? &*prior : nullptr);
  if (!reconstruction) {
    spdlog::debug("monocular init: frame {} vs {}: {} matches, R_H {:.2f}, no reconstruction", frame.id,
                  reference_->id, matches.size(), models.homography_ratio);
    return std::nullopt;
  }
  TwoViewInitialization out;
  out.reference = reference_;
  out.current_from_reference = reconstruction->cam2_from_cam1;
  out.model = reconstruction->model;
  out.parallax_deg = reconstruction->parallax_deg;
  out.num_matches = static_cast<int>(matches.size());
  for (size_t k = 0; k < matches.size(); ++k) {
    if (!reconstruction->triangulated[k]) continue;
    out.matches.push_back({matches[k].first, matches[k].second, reconstruction->points_cam1[k]});
  }
  spdlog::debug(
      "monocular init: frame {} vs {}: {} matches, {} triangulated ({}, R_H {:.2f}, parallax {:.1f} deg)",
      frame.id, reference_->id, matches.size(), out.matches.size(), geometry::to_string(out.model),
      models.homography_ratio, out.parallax_deg);
  return out;
}

std::optional<std::pair<std::shared_ptr<map::KeyFrame>, std::shared_ptr<map::KeyFrame>>> build_initial_map(
    map::Map& map, const TwoViewInitialization& init, map::Frame& current,
    const MonocularInitializerOptions& options, InitialMapPlacement* placement) {
  const map::Frame& ref = *init.reference;
  auto kf1 = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), ref.id, ref.timestamp_s, ref.camera,
                                             ref.levels, ref.features, geometry::SE3::identity());
  auto kf2 =
      std::make_shared<map::KeyFrame>(map.next_keyframe_id(), current.id, current.timestamp_s, current.camera,
                                      current.levels, current.features, init.current_from_reference);
  if (placement != nullptr && placement->parent) kf1->restore_parent(placement->parent);
  map.add_keyframe(kf1);
  map.add_keyframe(kf2);
  std::vector<std::shared_ptr<map::MapPoint>> points;
  points.reserve(init.matches.size());
  for (const auto& m : init.matches) {
    // Reference keyframe = the first one: the mapper ages points by keyframe id, and processes kf1 first.
    auto point = std::make_shared<map::MapPoint>(map.next_map_point_id(), m.point_reference, kf1, current.id);
    point->add_observation(kf1, m.reference_index);
    point->add_observation(kf2, m.current_index);
    kf1->add_map_point(m.reference_index, point);
    kf2->add_map_point(m.current_index, point);
    point->compute_distinctive_descriptor();
    point->update_normal_and_depth();
    map.add_map_point(point);
    points.push_back(std::move(point));
  }
  kf1->update_connections();
  kf2->update_connections();

  // Bundle adjustment of both keyframes and all points, the first keyframe fixed.
  std::vector<optim::BaKeyframe> ba_keyframes{{static_cast<int>(kf1->id), kf1->cam_from_world(), true},
                                              {static_cast<int>(kf2->id), kf2->cam_from_world(), false}};
  std::vector<optim::BaPoint> ba_points;
  std::vector<optim::BaObservation> observations;
  struct Link {
    std::shared_ptr<map::KeyFrame> keyframe;
    size_t point;
  };
  std::vector<Link> links;
  for (size_t k = 0; k < points.size(); ++k) {
    ba_points.push_back({static_cast<int>(k), points[k]->world()});
    for (const auto& [kf, index] :
         {std::pair{kf1, init.matches[k].reference_index}, std::pair{kf2, init.matches[k].current_index}}) {
      const cv::KeyPoint& kp = kf->features->keys_un[index];
      optim::BaObservation o;
      o.keyframe_id = static_cast<int>(kf->id);
      o.point_id = static_cast<int>(k);
      o.pixel = geometry::Vec2(kp.pt.x, kp.pt.y);
      o.inv_sigma2 = kf->levels->inv_sigma2[kp.octave];
      observations.push_back(o);
      links.push_back({kf, k});
    }
  }
  optim::BundleAdjustmentOptions ba_options;
  ba_options.first_pass_iterations = options.ba_iterations;
  ba_options.second_pass_iterations = options.ba_iterations / 2;
  const auto result =
      optim::local_bundle_adjustment(*kf1->camera, ba_keyframes, ba_points, observations, ba_options);
  kf2->set_cam_from_world(result.keyframes[1].cam_from_world);
  for (size_t k = 0; k < points.size(); ++k) points[k]->set_world(result.points[k].world);
  for (size_t index : result.outliers) {
    const Link& link = links[index];
    points[link.point]->erase_observation(link.keyframe->id);  // two-view point: now bad
  }

  // Scale: median depth of the first keyframe's points = 1 (or as the placement says).
  const float median_depth = kf1->scene_median_depth();
  const int tracked = kf2->tracked_map_points(1);
  if (!(median_depth > 0) || tracked < options.min_map_points) {
    spdlog::info(
        "monocular init at frame {} rejected: median depth {:.3f}, {} points after bundle adjustment",
        current.id, median_depth, tracked);
    if (placement == nullptr) {
      map.clear();
    } else {
      for (const auto& point : points) map.erase_map_point(point->id);
      map.erase_keyframe(kf2->id);
      map.erase_keyframe(kf1->id);
      // Keyframes hold strong links to their points and parent, points to their keyframes: cut them.
      if (placement->parent) placement->parent->erase_child(kf1->id);
      kf2->release_links();
      kf1->release_links();
    }
    return std::nullopt;
  }
  double scale = 1.0 / median_depth;
  geometry::SE3 world_from_reference;  // identity: the reference is the world's origin
  if (placement != nullptr) {
    const double baseline = kf2->cam_from_world().translation().norm();
    placement->scaled_by_baseline =
        baseline > 0 && placement->predicted_baseline >=
                            placement->min_baseline_share * placement->expected_median_depth;
    scale = placement->scaled_by_baseline ? placement->predicted_baseline / baseline
                                          : placement->expected_median_depth / median_depth;
    placement->scale = scale;
    world_from_reference = placement->reference_cam_from_world.inverse();
  }
  const geometry::SE3 pose2 = kf2->cam_from_world();
  const geometry::SE3 reference_from_world = world_from_reference.inverse();
  kf1->set_cam_from_world(reference_from_world);
  kf2->set_cam_from_world(geometry::SE3(pose2.rotation(), pose2.translation() * scale) * reference_from_world);
  std::fill(current.map_points.begin(), current.map_points.end(), nullptr);
  std::fill(current.outliers.begin(), current.outliers.end(), false);
  for (size_t k = 0; k < points.size(); ++k) {
    auto& point = points[k];
    if (point->is_bad()) continue;
    point->set_world(world_from_reference * (point->world() * scale));
    point->update_normal_and_depth();
    current.map_points[init.matches[k].current_index] = point;
  }
  map.erase_bad_map_points();
  kf1->update_connections();
  kf2->update_connections();
  current.cam_from_world = kf2->cam_from_world();
  spdlog::info("monocular map initialised at frame {} from frame {} ({}, parallax {:.1f} deg): {} points",
               current.id, ref.id, geometry::to_string(init.model), init.parallax_deg, map.num_map_points());
  return std::make_pair(kf1, kf2);
}

}  // namespace crowdslam::tracking
