#include "crowdslam/loop/loop_closer.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <unordered_set>

#include "crowdslam/geometry/sim3_solver.h"
#include "crowdslam/loop/loop_search.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/match/bow_search.h"
#include "crowdslam/optim/sim3_optimization.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/thread_priority.h"

namespace crowdslam::loop {

void LoopCloserOptions::check() const {
  auto require = [](bool ok, const char* key) {
    if (!ok) throw InputError(std::string("loop closing: invalid ") + key);
  };
  require(min_keyframes_since_loop >= 0, "min_keyframes_since_loop");
  require(min_map_keyframes >= 0, "min_map_keyframes");
  require(consistency_threshold >= 1, "consistency_threshold");
  require(min_bow_matches >= 3, "min_bow_matches");
  require(min_sim3_inliers >= 3, "min_sim3_inliers");
  require(min_total_matches >= min_sim3_inliers, "min_total_matches");
  require(covisible_confirmations >= 0, "covisible_confirmations");
  require(immediate_candidates >= 0, "immediate_candidates");
  require(essential_graph_min_weight >= 1, "essential_graph_min_weight");
  require(essential_graph_iterations >= 1, "essential_graph_iterations");
  require(global_ba_iterations >= 1, "global_ba_iterations");
}

LoopCloser::LoopCloser(const LoopCloserOptions& options, std::shared_ptr<map::Map> map,
                       const KeyframeDatabase* database, LocalMappingControl* mapper)
    : options_(options),
      map_(std::move(map)),
      database_(database),
      mapper_(mapper),
      detector_(options.consistency_threshold),
      global_ba_(map_, mapper, options.global_ba_iterations) {
  options_.check();
  if (options_.ground) global_ba_.set_ground(*options_.ground);
}

LoopCloser::~LoopCloser() { stop(); }

void LoopCloser::start() {
  if (worker_.joinable()) return;
  {
    std::lock_guard lock(queue_mutex_);
    stop_requested_ = false;
  }
  worker_ = std::thread([this] {
    util::set_thread_name("cs-loop");
    util::lower_thread_priority(options_.thread_nice);
    run();
  });
}

void LoopCloser::stop() {
  {
    std::lock_guard lock(queue_mutex_);
    stop_requested_ = true;
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
  global_ba_.wait();
}

void LoopCloser::stop_now() {
  {
    std::lock_guard lock(queue_mutex_);
    stop_requested_ = true;
    queue_.clear();
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();  // after a correction in progress, which may launch global BA
  global_ba_.abort();
}

void LoopCloser::run() {
  while (true) {
    std::shared_ptr<map::KeyFrame> keyframe;
    {
      std::unique_lock lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return stop_requested_ || !queue_.empty(); });
      if (queue_.empty()) return;
      keyframe = std::move(queue_.front());
      queue_.pop_front();
    }
    process_keyframe(keyframe, false);
  }
}

void LoopCloser::process_all() {
  while (true) {
    std::shared_ptr<map::KeyFrame> keyframe;
    {
      std::lock_guard lock(queue_mutex_);
      if (queue_.empty()) return;
      keyframe = std::move(queue_.front());
      queue_.pop_front();
    }
    process_keyframe(keyframe, true);
  }
}

void LoopCloser::insert_keyframe(std::shared_ptr<map::KeyFrame> keyframe) {
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(std::move(keyframe));
  }
  queue_cv_.notify_one();
}

void LoopCloser::reset() {
  global_ba_.abort();
  std::lock_guard lock(queue_mutex_);
  queue_.clear();
  detector_.reset();
  last_loop_keyframe_id_ = 0;
  any_loop_ = false;
}

LoopCloserStats LoopCloser::stats() const {
  std::lock_guard lock(stats_mutex_);
  LoopCloserStats copy = stats_;
  copy.global_ba = global_ba_.stats();
  return copy;
}

void LoopCloser::process_keyframe(const std::shared_ptr<map::KeyFrame>& keyframe, bool inline_mode) {
  if (!database_ || keyframe->is_bad() || !keyframe->features->has_bow()) return;
  const auto start = std::chrono::steady_clock::now();
  LoopDetector::Detection candidates;
  const bool too_early = map_->num_keyframes() < static_cast<size_t>(options_.min_map_keyframes) ||
                         (any_loop_ && keyframe->id < last_loop_keyframe_id_ + options_.min_keyframes_since_loop);
  if (!too_early) candidates = detector_.detect(*keyframe, *database_);
  Candidate loop;
  const bool consistent_accepted = !candidates.consistent.empty() && verify(keyframe, candidates.consistent, loop);
  bool confirmed = false;
  if (!consistent_accepted && options_.covisible_confirmations > 0 && options_.immediate_candidates > 0 &&
      !candidates.others.empty()) {
    auto& others = candidates.others;
    if (others.size() > static_cast<size_t>(options_.immediate_candidates)) {
      others.resize(static_cast<size_t>(options_.immediate_candidates));
    }
    confirmed = verify(keyframe, others, loop, options_.covisible_confirmations);
  }
  const bool accepted = consistent_accepted || confirmed;
  {
    std::lock_guard lock(stats_mutex_);
    ++stats_.keyframes_checked;
    stats_.candidates_consistent += static_cast<int>(candidates.consistent.size());
    if (!candidates.consistent.empty() && !consistent_accepted) ++stats_.candidates_rejected;
    if (confirmed) ++stats_.loops_confirmed_by_covisibles;
    stats_.detection_ms_total +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  if (!accepted) return;

  const auto correction_start = std::chrono::steady_clock::now();
  correct_loop(keyframe, loop);
  const double correction_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - correction_start).count();
  spdlog::info("loop closed: keyframe {} -> keyframe {} ({} matches, {:.0f} ms)", keyframe->id,
               loop.loop_keyframe->id, loop.matches, correction_ms);
  {
    std::lock_guard lock(stats_mutex_);
    stats_.loops.push_back({keyframe->id, loop.loop_keyframe->id, keyframe->timestamp_s,
                            loop.loop_keyframe->timestamp_s, loop.matches, correction_ms});
  }
  last_loop_keyframe_id_ = keyframe->id;
  any_loop_ = true;
  if (options_.global_ba) {
    if (inline_mode) {
      global_ba_.run();
    } else {
      global_ba_.launch();
    }
  }
}

namespace {

// Covisible keyframes tried when confirming a loop candidate that is not yet consistent.
constexpr size_t kConfirmingNeighbours = 5;

// 3D-3D correspondences from BoW matches: point i of kf1 with its match in kf2.
std::vector<geometry::Sim3Match> sim3_matches(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                                              const std::vector<std::shared_ptr<map::MapPoint>>& matches_12,
                                              std::vector<size_t>& keypoint_of_match) {
  std::vector<geometry::Sim3Match> out;
  keypoint_of_match.clear();
  const geometry::SE3 cam1_from_world = kf1.cam_from_world();
  const geometry::SE3 cam2_from_world = kf2.cam_from_world();
  const auto points1 = kf1.map_points();
  for (size_t i = 0; i < matches_12.size(); ++i) {
    const auto& p2 = matches_12[i];
    const auto& p1 = points1[i];
    if (!p1 || !p2 || p1->is_bad() || p2->is_bad()) continue;
    const long j = p2->index_in(kf2.id);
    if (j < 0) continue;
    const auto& key1 = kf1.features->keys_un[i];
    const auto& key2 = kf2.features->keys_un[static_cast<size_t>(j)];
    geometry::Sim3Match m;
    m.point_in_cam1 = cam1_from_world * p1->world();
    m.point_in_cam2 = cam2_from_world * p2->world();
    m.pixel1 = Eigen::Vector2d(key1.pt.x, key1.pt.y);
    m.pixel2 = Eigen::Vector2d(key2.pt.x, key2.pt.y);
    m.sigma2_1 = kf1.levels->sigma2[key1.octave];
    m.sigma2_2 = kf2.levels->sigma2[key2.octave];
    out.push_back(m);
    keypoint_of_match.push_back(i);
  }
  return out;
}

int count_matched(const std::vector<std::shared_ptr<map::MapPoint>>& matched) {
  int n = 0;
  for (const auto& p : matched) n += p ? 1 : 0;
  return n;
}

}  // namespace

int LoopCloser::covisible_confirmations(const map::KeyFrame& keyframe, const Candidate& candidate,
                                        int needed) const {
  const geometry::SE3 world_from_cam = keyframe.cam_from_world().inverse();
  int confirmed = 0;
  for (const auto& covisible : keyframe.best_covisible(kConfirmingNeighbours)) {
    if (confirmed >= needed) break;
    if (covisible->is_bad()) continue;
    // The covisible keyframe moved with the keyframe: its pose relative to it kept.
    const geometry::Sim3 cam_from_world =
        geometry::Sim3(covisible->cam_from_world() * world_from_cam) * candidate.cam_from_world;
    std::vector<std::shared_ptr<map::MapPoint>> matched(covisible->features->size());
    search_by_projection(*covisible, cam_from_world, candidate.loop_points, matched, 10.0);
    const int matches = count_matched(matched);
    spdlog::debug("loop candidate {}: {} matches in covisible keyframe {}", candidate.loop_keyframe->id, matches,
                  covisible->id);
    if (matches >= options_.min_total_matches) ++confirmed;
  }
  return confirmed;
}

bool LoopCloser::verify(const std::shared_ptr<map::KeyFrame>& keyframe,
                        const std::vector<std::shared_ptr<map::KeyFrame>>& candidates, Candidate& accepted,
                        int confirmations) {
  for (const auto& candidate : candidates) candidate->set_not_erase();
  bool found = false;
  for (const auto& candidate : candidates) {
    if (found || candidate->is_bad()) continue;
    std::vector<std::shared_ptr<map::MapPoint>> matches;
    const int bow_matches = match::search_by_bow(*keyframe, *candidate, matches, 0.75);
    spdlog::debug("loop candidate {} for keyframe {}: {} BoW matches", candidate->id, keyframe->id, bow_matches);
    if (bow_matches < options_.min_bow_matches) continue;
    std::vector<size_t> keypoint_of_match;
    const auto correspondences = sim3_matches(*keyframe, *candidate, matches, keypoint_of_match);
    geometry::Sim3SolverOptions solver_options;
    solver_options.fix_scale = options_.fix_scale;
    solver_options.min_inliers = options_.min_sim3_inliers;
    const auto ransac = geometry::solve_sim3_ransac(*keyframe->camera, *candidate->camera, correspondences,
                                                    solver_options);
    if (!ransac) {
      spdlog::debug("loop candidate {}: no Sim3 from {} matches", candidate->id, correspondences.size());
      continue;
    }
    // Keep the RANSAC inliers, then look for more matches through the Sim3.
    std::vector<std::shared_ptr<map::MapPoint>> inlier_matches(keyframe->features->size());
    for (size_t m = 0; m < correspondences.size(); ++m) {
      if (ransac->inliers[m]) inlier_matches[keypoint_of_match[m]] = matches[keypoint_of_match[m]];
    }
    search_by_sim3(*keyframe, *candidate, inlier_matches, ransac->cam1_from_cam2, 7.5);
    const auto refined_input = sim3_matches(*keyframe, *candidate, inlier_matches, keypoint_of_match);
    optim::Sim3OptimizationOptions optimisation_options;
    optimisation_options.fix_scale = options_.fix_scale;
    const auto refined = optim::optimize_sim3(*keyframe->camera, *candidate->camera, refined_input,
                                              std::vector<bool>(refined_input.size(), true), ransac->cam1_from_cam2,
                                              optimisation_options);
    spdlog::debug("loop candidate {}: Sim3 {} RANSAC inliers of {}, {} after refinement ({} matches)", candidate->id,
                  ransac->num_inliers, correspondences.size(), refined.num_inliers, refined_input.size());
    if (refined.num_inliers < options_.min_sim3_inliers) continue;

    // Corrected pose of the keyframe; matches of the loop's whole neighbourhood through it.
    Candidate c;
    c.loop_keyframe = candidate;
    c.cam_from_world = refined.cam1_from_cam2 * geometry::Sim3(candidate->cam_from_world());
    c.matched.assign(keyframe->features->size(), nullptr);
    for (size_t m = 0; m < refined_input.size(); ++m) {
      if (refined.inliers[m]) c.matched[keypoint_of_match[m]] = inlier_matches[keypoint_of_match[m]];
    }
    auto neighbourhood = candidate->connected_keyframes();
    neighbourhood.push_back(candidate);
    std::unordered_set<uint64_t> seen;
    for (const auto& kf : neighbourhood) {
      if (kf->is_bad()) continue;
      for (auto& p : kf->valid_map_points()) {
        if (seen.insert(p->id).second) c.loop_points.push_back(std::move(p));
      }
    }
    search_by_projection(*keyframe, c.cam_from_world, c.loop_points, c.matched, 10.0);
    c.matches = count_matched(c.matched);
    spdlog::debug("loop candidate {}: {} matches with the loop's neighbourhood", candidate->id, c.matches);
    if (c.matches >= options_.min_total_matches &&
        (confirmations == 0 || covisible_confirmations(*keyframe, c, confirmations) >= confirmations)) {
      accepted = std::move(c);
      found = true;
    }
  }
  for (const auto& candidate : candidates) {
    if (!found || candidate != accepted.loop_keyframe) candidate->set_erase(*map_);
  }
  return found;
}

}  // namespace crowdslam::loop
