#include "crowdslam/map/map_point.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/map/keyframe.h"

namespace crowdslam::map {

MapPoint::MapPoint(uint64_t id_in, const geometry::Vec3& world,
                   const std::shared_ptr<KeyFrame>& reference_keyframe, uint64_t first_frame_id_in)
    : id(id_in),
      first_keyframe_id(reference_keyframe ? reference_keyframe->id : 0),
      first_frame_id(first_frame_id_in),
      world_(world),
      reference_keyframe_(reference_keyframe) {}

uint64_t MapPoint::next_mark() {
  static std::atomic<uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

geometry::Vec3 MapPoint::world() const {
  std::lock_guard lock(position_mutex_);
  return world_;
}

void MapPoint::set_world(const geometry::Vec3& world) {
  std::lock_guard lock(position_mutex_);
  world_ = world;
}

geometry::Vec3 MapPoint::normal() const {
  std::lock_guard lock(position_mutex_);
  return normal_;
}

float MapPoint::min_distance() const {
  std::lock_guard lock(position_mutex_);
  return 0.8f * min_distance_;
}

float MapPoint::max_distance() const {
  std::lock_guard lock(position_mutex_);
  return 1.2f * max_distance_;
}

int MapPoint::predict_scale(float distance, const ScaleLevels& levels) const {
  ViewGeometry geometry;
  {
    std::lock_guard lock(position_mutex_);
    geometry.scale_distance = max_distance_;
  }
  return geometry.predict_scale(distance, levels);
}

int MapPoint::ViewGeometry::predict_scale(float distance, const ScaleLevels& levels) const {
  const float ratio = scale_distance / std::max(distance, 1e-6f);
  const int level = static_cast<int>(std::ceil(std::log(ratio) / levels.log_scale_factor));
  return std::clamp(level, 0, levels.num_levels - 1);
}

MapPoint::ViewGeometry MapPoint::view_geometry() const {
  std::lock_guard lock(position_mutex_);
  ViewGeometry geometry;
  geometry.world = world_;
  geometry.normal = normal_;
  geometry.min_distance = 0.8f * min_distance_;
  geometry.max_distance = 1.2f * max_distance_;
  geometry.scale_distance = max_distance_;
  return geometry;
}

namespace {
template <class It>
It lower_bound_id(It begin, It end, uint64_t keyframe_id) {
  return std::lower_bound(begin, end, keyframe_id,
                          [](const auto& entry, uint64_t id) { return entry.first < id; });
}
}  // namespace

MapPoint::Observations::iterator MapPoint::find_observation(uint64_t keyframe_id) {
  auto it = lower_bound_id(observations_.begin(), observations_.end(), keyframe_id);
  return it != observations_.end() && it->first == keyframe_id ? it : observations_.end();
}

MapPoint::Observations::const_iterator MapPoint::find_observation(uint64_t keyframe_id) const {
  auto it = lower_bound_id(observations_.cbegin(), observations_.cend(), keyframe_id);
  return it != observations_.cend() && it->first == keyframe_id ? it : observations_.cend();
}

void MapPoint::add_observation(const std::shared_ptr<KeyFrame>& keyframe, size_t index) {
  std::lock_guard lock(features_mutex_);
  auto it = lower_bound_id(observations_.begin(), observations_.end(), keyframe->id);
  if (it != observations_.end() && it->first == keyframe->id) return;
  observations_.insert(it, {keyframe->id, Observation{keyframe, index}});
  descriptor_stale_ = true;
  num_observations_ += keyframe->features->has_right(index) ? 2 : 1;
}

void MapPoint::erase_observation(uint64_t keyframe_id) {
  bool now_bad = false;
  {
    std::lock_guard lock(features_mutex_);
    auto it = find_observation(keyframe_id);
    if (it == observations_.end()) return;
    auto kf = it->second.keyframe.lock();
    const bool stereo = kf && kf->features->has_right(it->second.index);
    num_observations_ -= stereo ? 2 : 1;
    observations_.erase(it);
    descriptor_stale_ = true;
    auto ref = reference_keyframe_.lock();
    if ((!ref || ref->id == keyframe_id) && !observations_.empty()) {
      reference_keyframe_ = observations_.begin()->second.keyframe;
    }
    now_bad = num_observations_ <= 2;
  }
  if (now_bad) set_bad();
}

MapPoint::Observations MapPoint::observations() const {
  std::lock_guard lock(features_mutex_);
  return observations_;
}

int MapPoint::num_observations() const {
  std::lock_guard lock(features_mutex_);
  return num_observations_;
}

bool MapPoint::is_observed_by(uint64_t keyframe_id) const {
  std::lock_guard lock(features_mutex_);
  return find_observation(keyframe_id) != observations_.end();
}

long MapPoint::index_in(uint64_t keyframe_id) const {
  std::lock_guard lock(features_mutex_);
  auto it = find_observation(keyframe_id);
  return it == observations_.end() ? -1 : static_cast<long>(it->second.index);
}

std::shared_ptr<KeyFrame> MapPoint::reference_keyframe() const {
  std::lock_guard lock(features_mutex_);
  return reference_keyframe_.lock();
}

Descriptor MapPoint::descriptor() const {
  std::lock_guard lock(features_mutex_);
  return descriptor_;
}

void MapPoint::compute_distinctive_descriptor() {
  std::vector<const uint8_t*> descriptors;
  std::vector<std::shared_ptr<KeyFrame>> keep_alive;
  {
    // Under the lock without copying the observations: KeyFrame::is_bad() takes no lock and a keyframe's
    // features never change, so no other mutex is taken here.
    std::lock_guard lock(features_mutex_);
    if (!descriptor_stale_) return;  // computed from these observations already
    descriptor_stale_ = false;       // set again by any change from here on
    descriptors.reserve(observations_.size());
    keep_alive.reserve(observations_.size());
    for (const auto& [kf_id, obs] : observations_) {
      auto kf = obs.keyframe.lock();
      if (!kf) continue;
      const bool usable = !kf->is_bad();
      if (usable) descriptors.push_back(kf->features->descriptor(obs.index));
      keep_alive.push_back(std::move(kf));  // released after the lock, whatever its state
    }
  }
  if (descriptors.empty()) return;
  const size_t n = descriptors.size();
  std::vector<int> distances(n * n, 0);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      const int d = feature::hamming_distance(descriptors[i], descriptors[j]);
      distances[i * n + j] = d;
      distances[j * n + i] = d;
    }
  }
  // The descriptor with the least median distance to all others.
  int best_median = std::numeric_limits<int>::max();
  size_t best = 0;
  std::vector<int> row(n);
  for (size_t i = 0; i < n; ++i) {
    std::copy(distances.begin() + static_cast<long>(i * n),
              distances.begin() + static_cast<long>((i + 1) * n), row.begin());
    std::nth_element(row.begin(), row.begin() + static_cast<long>((n - 1) / 2), row.end());
    const int median = row[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  std::lock_guard lock(features_mutex_);
  std::copy(descriptors[best], descriptors[best] + 32, descriptor_.begin());
}

void MapPoint::set_descriptor(const uint8_t* descriptor) {
  std::lock_guard lock(features_mutex_);
  std::copy(descriptor, descriptor + 32, descriptor_.begin());
  descriptor_stale_ = true;
}

void MapPoint::update_normal_and_depth() {
  std::vector<std::shared_ptr<KeyFrame>> keyframes;  // a flat copy: no map nodes to allocate
  std::shared_ptr<KeyFrame> reference;
  {
    std::lock_guard lock(features_mutex_);
    if (bad_) return;
    keyframes.reserve(observations_.size());
    for (const auto& [kf_id, o] : observations_) {
      if (auto kf = o.keyframe.lock()) keyframes.push_back(std::move(kf));
    }
    reference = reference_keyframe_.lock();
  }
  if (keyframes.empty() || !reference) return;
  const geometry::Vec3 position = world();
  geometry::Vec3 normal_sum = geometry::Vec3::Zero();
  int count = 0;
  for (const auto& kf : keyframes) {
    normal_sum += (position - kf->camera_center()).normalized();
    ++count;
  }
  if (count == 0) return;
  const long ref_index = index_in(reference->id);
  if (ref_index < 0) return;
  const float distance = static_cast<float>((position - reference->camera_center()).norm());
  const int level = reference->features->keys_un[static_cast<size_t>(ref_index)].octave;
  const float level_scale = reference->levels->scale[level];
  const float top_scale = reference->levels->scale[reference->levels->num_levels - 1];
  std::lock_guard lock(position_mutex_);
  max_distance_ = distance * level_scale;
  min_distance_ = max_distance_ / top_scale;
  normal_ = normal_sum / count;
  normal_.normalize();
}

void MapPoint::increase_visible(int n) { visible_.fetch_add(n, std::memory_order_relaxed); }

void MapPoint::increase_found(int n) { found_.fetch_add(n, std::memory_order_relaxed); }

int MapPoint::record_motion(bool moving) {
  std::lock_guard lock(features_mutex_);
  static_assert(kMotionWindow == 8, "motion_bits_ holds 8 verdicts");
  motion_bits_ = static_cast<uint8_t>((motion_bits_ << 1) | (moving ? 1 : 0));
  return __builtin_popcount(motion_bits_);
}

int MapPoint::moving_run() const {
  std::lock_guard lock(features_mutex_);
  int run = 0;
  while (run < kMotionWindow && ((motion_bits_ >> run) & 1u)) ++run;
  return run;
}

int MapPoint::motion_score() const {
  std::lock_guard lock(features_mutex_);
  return __builtin_popcount(motion_bits_);
}

float MapPoint::found_ratio() const {
  return static_cast<float>(found_.load(std::memory_order_relaxed)) /
         static_cast<float>(std::max(1, visible_.load(std::memory_order_relaxed)));
}

int MapPoint::visible_count() const { return visible_.load(std::memory_order_relaxed); }

int MapPoint::found_count() const { return found_.load(std::memory_order_relaxed); }

bool MapPoint::is_bad() const { return bad_.load(std::memory_order_acquire); }

void MapPoint::set_bad() {
  Observations obs;
  {
    std::lock_guard lock(features_mutex_);
    if (bad_) return;
    bad_ = true;
    obs.swap(observations_);
    num_observations_ = 0;
  }
  for (const auto& [kf_id, o] : obs) {
    if (auto kf = o.keyframe.lock()) {
      // Only clear the slot if it still holds this point (it may have been replaced meanwhile).
      auto current = kf->map_point(o.index);
      if (current.get() == this) kf->erase_map_point(o.index);
    }
  }
}

void MapPoint::replace(const std::shared_ptr<MapPoint>& other) {
  if (!other || other.get() == this) return;
  Observations obs;
  int visible = 0;
  int found = 0;
  {
    std::lock_guard lock(features_mutex_);
    if (bad_) return;
    bad_ = true;
    obs.swap(observations_);
    num_observations_ = 0;
    visible = visible_;
    found = found_;
    replaced_by_ = other;
  }
  for (const auto& [kf_id, o] : obs) {
    auto kf = o.keyframe.lock();
    if (!kf) continue;
    if (!other->is_observed_by(kf_id)) {
      kf->replace_map_point(o.index, other);
      other->add_observation(kf, o.index);
    } else {
      auto current = kf->map_point(o.index);
      if (current.get() == this) kf->erase_map_point(o.index);
    }
  }
  other->increase_found(found);
  other->increase_visible(visible);
  other->compute_distinctive_descriptor();
}

std::shared_ptr<MapPoint> MapPoint::replaced_by() const {
  std::lock_guard lock(features_mutex_);
  return replaced_by_.lock();
}

MapPoint::SavedState MapPoint::saved_state() const {
  SavedState state;
  {
    std::lock_guard lock(position_mutex_);
    state.normal = normal_;
    state.min_distance = min_distance_;
    state.max_distance = max_distance_;
  }
  std::lock_guard lock(features_mutex_);
  state.visible = visible_;
  state.found = found_;
  return state;
}

void MapPoint::restore(const SavedState& state, const Descriptor& descriptor) {
  {
    std::lock_guard lock(position_mutex_);
    normal_ = state.normal;
    min_distance_ = state.min_distance;
    max_distance_ = state.max_distance;
  }
  std::lock_guard lock(features_mutex_);
  visible_ = state.visible;
  found_ = state.found;
  descriptor_ = descriptor;
}

}  // namespace crowdslam::map
