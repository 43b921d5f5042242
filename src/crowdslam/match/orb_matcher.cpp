#include "crowdslam/match/orb_matcher.h"

#include <cmath>
#include <unordered_map>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/match/rotation_histogram.h"

namespace crowdslam::match {

namespace {

using feature::hamming_distance;

bool slot_taken(const std::shared_ptr<map::MapPoint>& p) { return p && p->num_observations() > 0; }

void update_best(BestMatch& best, int index, int distance, int level) {
  if (distance < best.distance) {
    best.second_distance = best.distance;
    best.second_level = best.level;
    best.distance = distance;
    best.level = level;
    best.index = index;
  } else if (distance < best.second_distance) {
    best.second_distance = distance;
    best.second_level = level;
  }
}

}  // namespace

int search_local_points(map::Frame& frame, const std::vector<ProjectedPoint>& projected, double radius_factor,
                        double nn_ratio) {
  const map::FrameFeatures& f = *frame.features;
  const map::ScaleLevels& levels = *frame.levels;
  int matches = 0;
  for (const auto& [point, proj] : projected) {
    if (!point || point->is_bad()) continue;
    const int level = proj.predicted_level;
    const double radius = (proj.view_cos > 0.998 ? 2.5 : 4.0) * radius_factor * levels.scale[level];
    const auto candidates = f.grid.features_in_area(f.keys_un, static_cast<float>(proj.u), static_cast<float>(proj.v),
                                                    static_cast<float>(radius), level - 1, level);
    if (candidates.empty()) continue;
    const map::Descriptor descriptor = point->descriptor();
    BestMatch best;
    for (size_t idx : candidates) {
      if (slot_taken(frame.map_points[idx])) continue;
      if (proj.right_u >= 0 && f.has_right(idx) && std::abs(proj.right_u - f.right_u[idx]) > radius) continue;
      update_best(best, static_cast<int>(idx), hamming_distance(descriptor.data(), f.descriptor(idx)),
                  f.keys_un[idx].octave);
    }
    if (best.index < 0 || best.distance > kThHigh) continue;
    if (best.level == best.second_level && best.distance > nn_ratio * best.second_distance) continue;
    frame.map_points[static_cast<size_t>(best.index)] = point;
    ++matches;
  }
  return matches;
}

int search_from_last_frame(map::Frame& current, const map::Frame& last, double radius, bool check_orientation) {
  const map::FrameFeatures& cf = *current.features;
  const map::FrameFeatures& lf = *last.features;
  const map::ScaleLevels& levels = *current.levels;
  const geometry::PinholeCamera& cam = *current.camera;
  const geometry::SE3 cam_from_world = *current.cam_from_world;
  // Position of the current camera in the last camera's frame: moving forward or backward changes which
  // pyramid levels a point can appear at (only meaningful with metric depth).
  const geometry::Vec3 current_in_last = *last.cam_from_world * current.camera_center();
  const double baseline = cam.is_stereo() ? cam.baseline_m() : 0.0;
  const bool forward = cam.is_stereo() && current_in_last.z() > baseline;
  const bool backward = cam.is_stereo() && -current_in_last.z() > baseline;

  RotationHistogram histogram;
  std::vector<size_t> matched_indices;
  int matches = 0;
  for (size_t i = 0; i < last.map_points.size(); ++i) {
    const auto& point = last.map_points[i];
    if (!point || last.outliers[i] || point->is_bad()) continue;
    const geometry::Vec3 in_cam = cam_from_world * point->world();
    if (in_cam.z() <= 0) continue;
    const geometry::Vec2 pixel = cam.project(in_cam);
    if (!cf.grid.bounds().contains(pixel)) continue;
    const int last_level = lf.keys_un[i].octave;
    const double r = radius * levels.scale[last_level];
    int min_level = last_level - 1;
    int max_level = last_level + 1;
    if (forward) {
      min_level = last_level;
      max_level = -1;
    } else if (backward) {
      min_level = 0;
      max_level = last_level;
    }
    const auto candidates = cf.grid.features_in_area(cf.keys_un, static_cast<float>(pixel.x()),
                                                     static_cast<float>(pixel.y()), static_cast<float>(r),
                                                     std::max(0, min_level), max_level);
    if (candidates.empty()) continue;
    const map::Descriptor descriptor = point->descriptor();
    const double right_u = cam.is_stereo() ? pixel.x() - cam.bf / in_cam.z() : -1.0;
    BestMatch best;
    for (size_t idx : candidates) {
      if (slot_taken(current.map_points[idx])) continue;
      if (right_u >= 0 && cf.has_right(idx) && std::abs(right_u - cf.right_u[idx]) > r) continue;
      update_best(best, static_cast<int>(idx), hamming_distance(descriptor.data(), cf.descriptor(idx)),
                  cf.keys_un[idx].octave);
    }
    if (best.index < 0 || best.distance > kThHigh) continue;
    const size_t idx = static_cast<size_t>(best.index);
    current.map_points[idx] = point;
    ++matches;
    if (check_orientation) {
      histogram.add(lf.keys_un[i].angle - cf.keys_un[idx].angle, idx);
      matched_indices.push_back(idx);
    }
  }
  if (check_orientation) {
    for (size_t idx : histogram.rejected()) {
      current.map_points[idx].reset();
      --matches;
    }
  }
  return matches;
}

int search_keyframe_window(map::Frame& frame, const map::KeyFrame& keyframe, double radius, double nn_ratio,
                           bool check_orientation) {
  const map::FrameFeatures& ff = *frame.features;
  const map::FrameFeatures& kf = *keyframe.features;
  const auto kf_points = keyframe.map_points();
  // Best keyframe keypoint per frame keypoint (a frame keypoint is matched at most once).
  std::unordered_map<size_t, std::pair<size_t, int>> best_for_frame;  // frame idx -> (kf idx, distance)
  for (size_t i = 0; i < kf_points.size(); ++i) {
    const auto& point = kf_points[i];
    if (!point || point->is_bad()) continue;
    const cv::KeyPoint& kp = kf.keys_un[i];
    const auto candidates = ff.grid.features_in_area(ff.keys_un, kp.pt.x, kp.pt.y, static_cast<float>(radius),
                                                     std::max(0, kp.octave - 2), kp.octave + 2);
    BestMatch best;
    for (size_t idx : candidates) {
      if (slot_taken(frame.map_points[idx])) continue;
      update_best(best, static_cast<int>(idx), hamming_distance(kf.descriptor(i), ff.descriptor(idx)), 0);
    }
    if (best.index < 0 || best.distance > kThLow) continue;
    if (best.distance > nn_ratio * best.second_distance) continue;
    auto [it, inserted] = best_for_frame.try_emplace(static_cast<size_t>(best.index), i, best.distance);
    if (!inserted && best.distance < it->second.second) it->second = {i, best.distance};
  }
  RotationHistogram histogram;
  int matches = 0;
  for (const auto& [idx, match] : best_for_frame) {
    frame.map_points[idx] = kf_points[match.first];
    ++matches;
    if (check_orientation) histogram.add(kf.keys_un[match.first].angle - ff.keys_un[idx].angle, idx);
  }
  if (check_orientation) {
    for (size_t idx : histogram.rejected()) {
      frame.map_points[idx].reset();
      --matches;
    }
  }
  return matches;
}

geometry::Mat3 fundamental_between(const map::KeyFrame& kf1, const map::KeyFrame& kf2) {
  const geometry::SE3 cam2_from_cam1 = kf2.cam_from_world() * kf1.world_from_cam();
  const geometry::Mat3 k1_inv = kf1.camera->intrinsic_matrix().inverse();
  const geometry::Mat3 k2_inv = kf2.camera->intrinsic_matrix().inverse();
  const geometry::Mat3 essential = geometry::skew(cam2_from_cam1.translation()) * cam2_from_cam1.rotation_matrix();
  return k2_inv.transpose() * essential * k1_inv;
}

namespace {
// The candidate test of the triangulation search: kf1 keypoint i against kf2 keypoint j.
class TriangulationCandidates {
 public:
  TriangulationCandidates(const map::KeyFrame& kf1, const map::KeyFrame& kf2, const geometry::Mat3& fundamental_21)
      : f1_(*kf1.features), f2_(*kf2.features), levels_(*kf2.levels), fundamental_21_(fundamental_21) {
    // Epipole: kf1's camera centre seen from kf2.
    const geometry::Vec3 c1_in_2 = kf2.cam_from_world() * kf1.camera_center();
    epipole_ = kf2.camera->project(c1_in_2);
    epipole_valid_ = c1_in_2.z() > 0;
  }

  // Prepares keypoint i of kf1; false when it has no usable epipolar line.
  bool start(size_t i) {
    const cv::KeyPoint& kp1 = f1_.keys_un[i];
    line_ = fundamental_21_ * geometry::Vec3(kp1.pt.x, kp1.pt.y, 1.0);
    line_norm2_ = line_.x() * line_.x() + line_.y() * line_.y();
    descriptor_ = f1_.descriptor(i);
    best_distance_ = kThLow;
    best_index_ = -1;
    return line_norm2_ > 0;
  }

  void consider(size_t j) {
    const int distance = hamming_distance(descriptor_, f2_.descriptor(j));
    if (distance > best_distance_) return;
    const cv::KeyPoint& kp2 = f2_.keys_un[j];
    if (!f2_.has_right(j) && epipole_valid_) {
      const double ex = epipole_.x() - kp2.pt.x;
      const double ey = epipole_.y() - kp2.pt.y;
      if (ex * ex + ey * ey < 100.0 * levels_.scale[kp2.octave]) return;
    }
    const double num = line_.x() * kp2.pt.x + line_.y() * kp2.pt.y + line_.z();
    if (num * num / line_norm2_ >= 3.84 * levels_.sigma2[kp2.octave]) return;
    best_distance_ = distance;
    best_index_ = static_cast<int>(j);
  }

  [[nodiscard]] int best() const { return best_index_; }

 private:
  const map::FrameFeatures& f1_;
  const map::FrameFeatures& f2_;
  const map::ScaleLevels& levels_;
  const geometry::Mat3& fundamental_21_;
  geometry::Vec2 epipole_;
  bool epipole_valid_ = false;
  geometry::Vec3 line_;
  double line_norm2_ = 0;
  const uint8_t* descriptor_ = nullptr;
  int best_distance_ = kThLow;
  int best_index_ = -1;
};
}  // namespace

std::vector<std::pair<size_t, size_t>> search_for_triangulation(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                                                                const geometry::Mat3& fundamental_21,
                                                                bool only_stereo, bool check_orientation) {
  const map::FrameFeatures& f1 = *kf1.features;
  const map::FrameFeatures& f2 = *kf2.features;
  const auto points1 = kf1.map_points();
  const auto points2 = kf2.map_points();
  std::vector<bool> free1(points1.size()), free2(points2.size());
  for (size_t i = 0; i < points1.size(); ++i) free1[i] = !points1[i] && (!only_stereo || f1.has_right(i));
  for (size_t j = 0; j < points2.size(); ++j) free2[j] = !points2[j] && (!only_stereo || f2.has_right(j));
  std::vector<bool> matched2(points2.size(), false);
  std::vector<std::pair<size_t, size_t>> matches;
  RotationHistogram histogram;
  TriangulationCandidates candidates(kf1, kf2, fundamental_21);
  const auto accept = [&](size_t i) {
    const int best = candidates.best();
    if (best < 0) return;
    matched2[static_cast<size_t>(best)] = true;
    if (check_orientation) histogram.add(f1.keys_un[i].angle - f2.keys_un[static_cast<size_t>(best)].angle, matches.size());
    matches.emplace_back(i, static_cast<size_t>(best));
  };
  if (!f1.bow_features.empty() && !f2.bow_features.empty()) {
    // ORB-SLAM2's idea: only keypoints under the same vocabulary node (direct index) are compared.
    auto it1 = f1.bow_features.begin();
    auto it2 = f2.bow_features.begin();
    while (it1 != f1.bow_features.end() && it2 != f2.bow_features.end()) {
      if (it1->first < it2->first) {
        it1 = f1.bow_features.lower_bound(it2->first);
        continue;
      }
      if (it2->first < it1->first) {
        it2 = f2.bow_features.lower_bound(it1->first);
        continue;
      }
      for (const unsigned i : it1->second) {
        if (!free1[i] || !candidates.start(i)) continue;
        for (const unsigned j : it2->second) {
          if (free2[j] && !matched2[j]) candidates.consider(j);
        }
        accept(i);
      }
      ++it1;
      ++it2;
    }
  } else {  // no vocabulary: every free pair
    std::vector<size_t> free2_list;
    for (size_t j = 0; j < points2.size(); ++j) {
      if (free2[j]) free2_list.push_back(j);
    }
    for (size_t i = 0; i < points1.size(); ++i) {
      if (!free1[i] || !candidates.start(i)) continue;
      for (size_t j : free2_list) {
        if (!matched2[j]) candidates.consider(j);
      }
      accept(i);
    }
  }
  if (check_orientation) {
    auto rejected = histogram.rejected();
    std::vector<bool> drop(matches.size(), false);
    for (size_t k : rejected) drop[k] = true;
    std::vector<std::pair<size_t, size_t>> kept;
    for (size_t k = 0; k < matches.size(); ++k) {
      if (!drop[k]) kept.push_back(matches[k]);
    }
    matches.swap(kept);
  }
  return matches;
}

int fuse(const std::shared_ptr<map::KeyFrame>& keyframe, const std::vector<std::shared_ptr<map::MapPoint>>& points,
         double radius) {
  const map::FrameFeatures& f = *keyframe->features;
  const map::ScaleLevels& levels = *keyframe->levels;
  const geometry::PinholeCamera& cam = *keyframe->camera;
  const geometry::SE3 cam_from_world = keyframe->cam_from_world();
  const geometry::Vec3 centre = keyframe->camera_center();
  int fused = 0;
  for (const auto& point : points) {
    if (!point || point->is_bad() || point->is_observed_by(keyframe->id)) continue;
    const map::MapPoint::ViewGeometry view = point->view_geometry();
    const geometry::Vec3& world = view.world;
    const geometry::Vec3 in_cam = cam_from_world * world;
    if (in_cam.z() <= 0) continue;
    const geometry::Vec2 pixel = cam.project(in_cam);
    if (!f.grid.bounds().contains(pixel)) continue;
    const geometry::Vec3 ray = world - centre;
    const double distance = ray.norm();
    if (distance < view.min_distance || distance > view.max_distance) continue;
    if (ray.dot(view.normal) < 0.5 * distance) continue;
    const int level = view.predict_scale(static_cast<float>(distance), levels);
    const double r = radius * levels.scale[level];
    const auto candidates = f.grid.features_in_area(f.keys_un, static_cast<float>(pixel.x()),
                                                    static_cast<float>(pixel.y()), static_cast<float>(r));
    const double right_u = cam.is_stereo() ? pixel.x() - cam.bf / in_cam.z() : -1.0;
    const map::Descriptor descriptor = point->descriptor();
    int best_distance = 256;
    int best_index = -1;
    for (size_t idx : candidates) {
      const cv::KeyPoint& kp = f.keys_un[idx];
      if (kp.octave < level - 1 || kp.octave > level) continue;
      const double ex = pixel.x() - kp.pt.x;
      const double ey = pixel.y() - kp.pt.y;
      const double inv_sigma2 = levels.inv_sigma2[kp.octave];
      if (f.has_right(idx) && right_u >= 0) {
        const double er = right_u - f.right_u[idx];
        if ((ex * ex + ey * ey + er * er) * inv_sigma2 > 7.8) continue;
      } else if ((ex * ex + ey * ey) * inv_sigma2 > 5.99) {
        continue;
      }
      const int d = hamming_distance(descriptor.data(), f.descriptor(idx));
      if (d < best_distance) {
        best_distance = d;
        best_index = static_cast<int>(idx);
      }
    }
    if (best_index < 0 || best_distance > kThLow) continue;
    const size_t idx = static_cast<size_t>(best_index);
    if (auto existing = keyframe->map_point(idx)) {
      if (!existing->is_bad()) {
        if (existing->num_observations() > point->num_observations()) {
          point->replace(existing);
        } else {
          existing->replace(point);
        }
      }
    } else {
      point->add_observation(keyframe, idx);
      keyframe->add_map_point(idx, point);
    }
    ++fused;
  }
  return fused;
}

}  // namespace crowdslam::match
