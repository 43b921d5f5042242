#include "crowdslam/tracking/relocalizer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <unordered_set>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/match/bow_search.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/tracking/pose_refinement.h"

namespace crowdslam::tracking {

namespace {

// Frame keypoint index -> map point, by nearest descriptor with a ratio test (each map point used once).
std::vector<std::pair<size_t, std::shared_ptr<map::MapPoint>>> match_by_descriptor(
    const map::Frame& frame, const std::vector<std::shared_ptr<map::MapPoint>>& points, double ratio,
    int max_distance) {
  const auto& f = *frame.features;
  std::vector<map::Descriptor> descriptors;
  descriptors.reserve(points.size());
  for (const auto& p : points) descriptors.push_back(p->descriptor());
  // Best frame keypoint per map point.
  std::vector<std::pair<size_t, std::shared_ptr<map::MapPoint>>> matches;
  std::vector<int> taken_distance(f.size(), 257);
  std::vector<int> taken_by(f.size(), -1);
  for (size_t k = 0; k < points.size(); ++k) {
    int best = 257, second = 257;
    int best_index = -1;
    for (size_t i = 0; i < f.size(); ++i) {
      const int d = feature::hamming_distance(descriptors[k].data(), f.descriptor(i));
      if (d < best) {
        second = best;
        best = d;
        best_index = static_cast<int>(i);
      } else if (d < second) {
        second = d;
      }
    }
    if (best_index < 0 || best > max_distance || best > ratio * second) continue;
    const size_t i = static_cast<size_t>(best_index);
    if (best < taken_distance[i]) {
      taken_distance[i] = best;
      taken_by[i] = static_cast<int>(k);
    }
  }
  for (size_t i = 0; i < f.size(); ++i) {
    if (taken_by[i] >= 0) matches.emplace_back(i, points[static_cast<size_t>(taken_by[i])]);
  }
  return matches;
}

// Frame keypoint index -> map point through the vocabulary's direct index.
std::vector<std::pair<size_t, std::shared_ptr<map::MapPoint>>> match_by_bow(const map::Frame& frame,
                                                                            const map::KeyFrame& candidate,
                                                                            double ratio) {
  std::vector<std::shared_ptr<map::MapPoint>> slots;
  match::search_by_bow(candidate, frame, slots, ratio, true);
  std::vector<std::pair<size_t, std::shared_ptr<map::MapPoint>>> matches;
  for (size_t i = 0; i < slots.size(); ++i) {
    if (slots[i]) matches.emplace_back(i, std::move(slots[i]));
  }
  return matches;
}

// Optimises the pose and drops the outlier matches; returns the inliers.
int optimize_and_count(map::Frame& frame, const optim::PoseOptimizerOptions& pose_options) {
  const int inliers = optimize_frame_pose(frame, pose_options);
  discard_outliers_count_map_points(frame);
  return inliers;
}

}  // namespace

std::shared_ptr<map::KeyFrame> Relocalizer::relocalize(map::Frame& frame,
                                                       const std::vector<std::shared_ptr<map::KeyFrame>>& candidates,
                                                       const optim::PoseOptimizerOptions& pose_options) const {
  const bool frame_bow = frame.features->has_bow();
  // Bag-of-words matching is cheap: match every candidate first and try the best matched first.
  std::vector<std::pair<std::shared_ptr<map::KeyFrame>, Matches>> by_bow;
  for (const auto& candidate : candidates) {
    if (!candidate || candidate->is_bad()) continue;
    if (frame_bow && candidate->features->has_bow()) {
      auto matches = match_by_bow(frame, *candidate, options_.ratio);
      if (static_cast<int>(matches.size()) >= options_.min_matches) by_bow.emplace_back(candidate, std::move(matches));
      continue;
    }
    // Brute force, in the order given.
    const auto points = candidate->valid_map_points();
    if (static_cast<int>(points.size()) < options_.min_matches) continue;
    const auto matches = match_by_descriptor(frame, points, options_.ratio, options_.max_distance);
    if (static_cast<int>(matches.size()) < options_.min_matches) continue;
    if (try_candidate(frame, *candidate, matches, pose_options)) return candidate;
  }
  std::stable_sort(by_bow.begin(), by_bow.end(),
                   [](const auto& a, const auto& b) { return a.second.size() > b.second.size(); });
  for (const auto& [candidate, matches] : by_bow) {
    if (try_candidate(frame, *candidate, matches, pose_options)) return candidate;
  }
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  frame.cam_from_world.reset();
  return nullptr;
}

bool Relocalizer::try_candidate(map::Frame& frame, const map::KeyFrame& candidate, const Matches& matches,
                                const optim::PoseOptimizerOptions& pose_options) const {
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);

  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const auto& [i, p] : matches) {
    const geometry::Vec3 w = p->world();
    object.emplace_back(w.x(), w.y(), w.z());
    image.emplace_back(frame.features->keys_un[i].pt.x, frame.features->keys_un[i].pt.y);
  }
  const auto& cam = *frame.camera;
  const cv::Mat k = (cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  const bool ok = cv::solvePnPRansac(object, image, k, cv::Mat(), rvec, tvec, false, options_.ransac_iterations,
                                     static_cast<float>(options_.ransac_reprojection_px), 0.99, inliers,
                                     cv::SOLVEPNP_EPNP);
  if (!ok || static_cast<int>(inliers.size()) < options_.min_pnp_inliers) return false;
  cv::Mat rotation;
  cv::Rodrigues(rvec, rotation);
  geometry::Mat3 r;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) r(a, b) = rotation.at<double>(a, b);
  }
  frame.cam_from_world = geometry::SE3(r, geometry::Vec3(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  for (int index : inliers) {
    const auto& [i, p] = matches[static_cast<size_t>(index)];
    frame.map_points[i] = p;
  }
  int good = optimize_and_count(frame, pose_options);
  if (good < options_.min_optimized_inliers) return false;

  // Too few inliers: more matches by projecting the candidate's neighbourhood with the new pose (wide
  // window), optimise again; if that lands between retry_min_inliers and min_final_inliers, a narrow
  // search with the better pose and a tighter descriptor threshold (ORB-SLAM2's two stages).
  if (good < options_.min_final_inliers) {
    const int additional = search_by_projection(frame, candidate, options_.wide_radius_factor, kNoDistanceLimit);
    if (good + additional < options_.min_final_inliers) return false;
    good = optimize_and_count(frame, pose_options);
    if (good > options_.retry_min_inliers && good < options_.min_final_inliers) {
      const int more = search_by_projection(frame, candidate, options_.narrow_radius_factor, options_.max_distance);
      if (good + more >= options_.min_final_inliers) good = optimize_and_count(frame, pose_options);
    }
  }
  spdlog::debug("relocalisation against keyframe {}: {} matches, {} PnP inliers, {} final inliers", candidate.id,
                matches.size(), inliers.size(), good);
  return good >= options_.min_final_inliers;
}

int Relocalizer::search_by_projection(map::Frame& frame, const map::KeyFrame& candidate, double radius_factor,
                                      int max_distance) const {
  std::unordered_set<const map::MapPoint*> already;
  std::vector<bool> was_free(frame.map_points.size());
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    const auto& p = frame.map_points[i];
    was_free[i] = !p;
    if (p) already.insert(p.get());
  }
  std::vector<match::ProjectedPoint> projected;
  std::unordered_set<uint64_t> seen;
  auto add_points = [&](const map::KeyFrame& kf) {
    for (auto& p : kf.valid_map_points()) {
      if (already.count(p.get()) || !seen.insert(p->id).second) continue;
      if (auto projection = frame.project(*p, 0.5)) projected.push_back({p, *projection});
    }
  };
  add_points(candidate);
  for (const auto& neighbour : candidate.best_covisible(10)) add_points(*neighbour);
  match::search_local_points(frame, projected, radius_factor, 0.9);
  int added = 0;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    auto& p = frame.map_points[i];
    if (!was_free[i] || !p) continue;
    if (max_distance != kNoDistanceLimit &&
        feature::hamming_distance(p->descriptor().data(), frame.features->descriptor(i)) > max_distance) {
      p.reset();
      continue;
    }
    ++added;
  }
  return added;
}

}  // namespace crowdslam::tracking
