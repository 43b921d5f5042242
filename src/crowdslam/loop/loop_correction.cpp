// Loop correction: moves the current keyframe's neighbourhood to where the loop says it is, fuses the
// loop's points, optimises the essential graph and records the loop edge.
#include <spdlog/spdlog.h>

#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "crowdslam/loop/loop_closer.h"
#include "crowdslam/loop/loop_search.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/optim/pose_graph.h"

namespace crowdslam::loop {
namespace {

using KeyframePtr = std::shared_ptr<map::KeyFrame>;
using SimByKeyframe = std::map<uint64_t, geometry::Sim3>;  // keyframe id -> cam_from_world

std::set<uint64_t> ids_of(const std::vector<KeyframePtr>& keyframes) {
  std::set<uint64_t> ids;
  for (const auto& kf : keyframes) ids.insert(kf->id);
  return ids;
}

// Essential graph: every keyframe a node (starting from its corrected pose if it has one), the loop
// keyframe fixed; edges: spanning tree, existing loop edges, covisibility >= min_weight, and the new
// loop connections. Relative measurements come from the poses before correction, except for the new
// loop connections, which come from the corrected poses.
void optimise_essential_graph(map::Map& map, const KeyframePtr& loop_keyframe, const KeyframePtr& current,
                              const SimByKeyframe& corrected, const SimByKeyframe& uncorrected,
                              const std::map<uint64_t, std::set<uint64_t>>& loop_connections,
                              const std::unordered_map<uint64_t, uint64_t>& corrected_by,
                              const LoopCloserOptions& options) {
  std::vector<KeyframePtr> keyframes;
  for (auto& kf : map.keyframes()) {
    if (!kf->is_bad()) keyframes.push_back(std::move(kf));
  }
  std::unordered_map<uint64_t, geometry::Sim3> start;  // estimate before optimisation
  std::vector<optim::PoseGraphNode> nodes;
  for (const auto& kf : keyframes) {
    const auto it = corrected.find(kf->id);
    const geometry::Sim3 pose = it != corrected.end() ? it->second : geometry::Sim3(kf->cam_from_world());
    start[kf->id] = pose;
    nodes.push_back({static_cast<int>(kf->id), pose, kf == loop_keyframe});
  }
  auto measured_pose = [&](uint64_t id) {  // the pose relative measurements are taken from
    const auto it = uncorrected.find(id);
    return it != uncorrected.end() ? it->second : start.at(id);
  };
  std::vector<optim::PoseGraphEdge> edges;
  std::set<std::pair<uint64_t, uint64_t>> inserted;
  auto add_edge = [&](uint64_t from, uint64_t to, const geometry::Sim3& to_from_from) {
    const auto key = std::minmax(from, to);
    if (!inserted.insert(key).second) return;
    edges.push_back({static_cast<int>(from), static_cast<int>(to), to_from_from, 1.0});
  };
  // New loop connections (corrected poses on both sides).
  for (const auto& [id, connected] : loop_connections) {
    if (!start.count(id)) continue;
    const KeyframePtr kf = map.keyframe(id);
    for (uint64_t other : connected) {
      if (!start.count(other)) continue;
      const bool is_loop_pair = (id == current->id && other == loop_keyframe->id);
      if (!is_loop_pair && (!kf || kf->weight(other) < options.essential_graph_min_weight)) continue;
      add_edge(id, other, start.at(other) * start.at(id).inverse());
    }
  }
  for (const auto& kf : keyframes) {
    const geometry::Sim3 world_from_i = measured_pose(kf->id).inverse();
    auto relative = [&](uint64_t other) { return measured_pose(other) * world_from_i; };
    if (auto parent = kf->parent(); parent && start.count(parent->id)) add_edge(kf->id, parent->id, relative(parent->id));
    for (const auto& loop_kf : kf->loop_edges()) {
      if (loop_kf->id < kf->id && start.count(loop_kf->id)) add_edge(kf->id, loop_kf->id, relative(loop_kf->id));
    }
    const auto parent = kf->parent();
    for (const auto& neighbour : kf->covisible_by_weight(options.essential_graph_min_weight)) {
      if (neighbour->is_bad() || neighbour->id >= kf->id || !start.count(neighbour->id)) continue;
      if (parent && neighbour->id == parent->id) continue;
      add_edge(kf->id, neighbour->id, relative(neighbour->id));
    }
  }
  optim::PoseGraphOptions graph_options;
  graph_options.fix_scale = options.fix_scale;
  graph_options.iterations = options.essential_graph_iterations;
  const auto result = optim::optimize_pose_graph(nodes, edges, graph_options);

  std::lock_guard map_lock(map.update_mutex());
  std::unordered_map<uint64_t, geometry::Sim3> optimised;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    optimised[keyframes[i]->id] = result.nodes[i].cam_from_world;
    keyframes[i]->set_cam_from_world(result.nodes[i].cam_from_world.to_se3());
  }
  // Points move with the keyframe that corrected them, else with their reference keyframe, else with any
  // keyframe that observes them.
  for (const auto& point : map.map_points()) {
    if (point->is_bad()) continue;
    uint64_t anchor = 0;
    bool found = false;
    if (const auto it = corrected_by.find(point->id); it != corrected_by.end() && start.count(it->second)) {
      anchor = it->second;
      found = true;
    } else if (const auto reference = point->reference_keyframe(); reference && start.count(reference->id)) {
      anchor = reference->id;
      found = true;
    } else {
      for (const auto& [kf_id, obs] : point->observations()) {
        if (start.count(kf_id)) {
          anchor = kf_id;
          found = true;
          break;
        }
      }
    }
    if (!found) continue;
    const geometry::Vec3 in_cam = start.at(anchor) * point->world();
    point->set_world(optimised.at(anchor).inverse() * in_cam);
    point->update_normal_and_depth();
  }
  spdlog::debug("essential graph: {} nodes, {} edges, cost {:.3g} -> {:.3g}", nodes.size(), edges.size(),
                result.initial_cost, result.final_cost);
}

}  // namespace

void LoopCloser::correct_loop(const KeyframePtr& keyframe, const Candidate& loop) {
  if (mapper_) mapper_->request_pause();
  global_ba_.abort();
  if (mapper_) mapper_->wait_until_paused();

  keyframe->update_connections();
  std::vector<KeyframePtr> neighbourhood = keyframe->connected_keyframes();
  neighbourhood.push_back(keyframe);

  // Corrected poses of the neighbourhood: each keeps its pose relative to the current keyframe.
  SimByKeyframe corrected;
  SimByKeyframe uncorrected;
  std::unordered_map<uint64_t, uint64_t> corrected_by;  // map point id -> keyframe whose correction moved it
  const geometry::SE3 world_from_current = keyframe->world_from_cam();
  for (const auto& kf : neighbourhood) {
    const geometry::SE3 pose = kf->cam_from_world();
    uncorrected[kf->id] = geometry::Sim3(pose);
    corrected[kf->id] = kf == keyframe ? loop.cam_from_world : geometry::Sim3(pose * world_from_current) * loop.cam_from_world;
  }
  {
    std::lock_guard map_lock(map_->update_mutex());
    for (const auto& kf : neighbourhood) {
      const geometry::Sim3 world_from_corrected = corrected.at(kf->id).inverse();
      const geometry::Sim3& uncorrected_pose = uncorrected.at(kf->id);
      for (const auto& point : kf->valid_map_points()) {
        if (!corrected_by.emplace(point->id, kf->id).second) continue;
        point->set_world(world_from_corrected * (uncorrected_pose * point->world()));
        point->update_normal_and_depth();
      }
      kf->set_cam_from_world(corrected.at(kf->id).to_se3());
      kf->update_connections();
    }
    // The loop's points replace the current keyframe's matched points.
    for (size_t i = 0; i < loop.matched.size(); ++i) {
      const auto& loop_point = loop.matched[i];
      if (!loop_point || loop_point->is_bad()) continue;
      if (auto existing = keyframe->map_point(i)) {
        if (existing != loop_point && !existing->is_bad()) existing->replace(loop_point);
      } else {
        loop_point->add_observation(keyframe, i);
        keyframe->add_map_point(i, loop_point);
        loop_point->compute_distinctive_descriptor();
      }
    }
  }
  // Fuse the loop's points into the corrected neighbourhood.
  for (const auto& kf : neighbourhood) {
    std::vector<std::shared_ptr<map::MapPoint>> replace;
    fuse_by_projection(kf, corrected.at(kf->id), loop.loop_points, 4.0, replace);
    std::lock_guard map_lock(map_->update_mutex());
    for (size_t k = 0; k < replace.size(); ++k) {
      if (replace[k] && !replace[k]->is_bad() && !loop.loop_points[k]->is_bad()) replace[k]->replace(loop.loop_points[k]);
    }
  }
  map_->erase_bad_map_points();

  // New links created by the loop: neighbours gained through the fusion.
  std::map<uint64_t, std::set<uint64_t>> loop_connections;
  const std::set<uint64_t> neighbourhood_ids = ids_of(neighbourhood);
  for (const auto& kf : neighbourhood) {
    const std::set<uint64_t> before = ids_of(kf->connected_keyframes());
    kf->update_connections();
    for (const auto& other : kf->connected_keyframes()) {
      if (!before.count(other->id) && !neighbourhood_ids.count(other->id)) loop_connections[kf->id].insert(other->id);
    }
  }
  loop_connections[keyframe->id].insert(loop.loop_keyframe->id);

  optimise_essential_graph(*map_, loop.loop_keyframe, keyframe, corrected, uncorrected, loop_connections,
                           corrected_by, options_);
  loop.loop_keyframe->add_loop_edge(keyframe);
  keyframe->add_loop_edge(loop.loop_keyframe);
  loop.loop_keyframe->set_erase(*map_);
  map_->notify_big_change();
  if (mapper_) mapper_->resume();
}

}  // namespace crowdslam::loop
