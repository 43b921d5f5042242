#include "crowdslam/geometry/ground_plane.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "crowdslam/util/error.h"

namespace crowdslam::geometry {

void GroundPlaneOptions::check() const {
  auto fail = [](const std::string& what) { return InputError("ground plane: " + what); };
  if (!(max_tilt_deg > 0 && max_tilt_deg < 90)) throw fail("max_tilt_deg must be in (0, 90)");
  if (!(inlier_ratio > 0 && inlier_ratio < 1)) throw fail("inlier_ratio must be in (0, 1)");
  if (!(min_below_ratio >= 0)) throw fail("min_below_ratio must be >= 0");
  if (min_inliers < 3) throw fail("min_inliers must be >= 3");
  if (iterations < 1) throw fail("iterations must be >= 1");
  if (!(consensus_deg > 0 && consensus_deg < 90)) throw fail("consensus_deg must be in (0, 90)");
  if (!(max_normal_change_deg > 0 && max_normal_change_deg < 90)) throw fail("max_normal_change_deg must be in (0, 90)");
  if (!(max_lateral_ratio > 0)) throw fail("max_lateral_ratio must be > 0");
  if (!(max_height_change > 0)) throw fail("max_height_change must be > 0");
  if (!(keyframe_sigma > 0 && keyframe_sigma <= 1)) throw fail("keyframe_sigma must be in (0, 1]");
}

namespace {

std::vector<std::size_t> inliers_of(const std::vector<Vec3>& points, const std::vector<std::size_t>& candidates,
                                    const Vec3& normal, double distance, double ratio) {
  std::vector<std::size_t> inliers;
  const double tolerance = ratio * distance;
  for (std::size_t i : candidates) {
    if (std::abs(normal.dot(points[i]) - distance) < tolerance) inliers.push_back(i);
  }
  return inliers;
}

std::vector<std::size_t> candidates_below(const std::vector<Vec3>& points, const GroundPlaneOptions& options) {
  std::vector<std::size_t> candidates;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    if (p.z() > 0 && p.y() > options.min_below_ratio * p.z()) candidates.push_back(i);
  }
  return candidates;
}

// The height (distance along `normal`) that most candidates lie at, within ratio of it; 0 when fewer than
// min_inliers do.
double height_mode(const std::vector<Vec3>& points, const std::vector<std::size_t>& candidates, const Vec3& normal,
                   double ratio, int min_inliers) {
  std::vector<double> heights;
  for (std::size_t i : candidates) {
    const double h = normal.dot(points[i]);
    if (h > 0) heights.push_back(h);
  }
  std::sort(heights.begin(), heights.end());
  std::size_t best_count = 0;
  double best = 0;
  std::size_t lo = 0;
  std::size_t hi = 0;
  for (const double h : heights) {
    while (heights[lo] < h * (1 - ratio)) ++lo;
    while (hi < heights.size() && heights[hi] <= h * (1 + ratio)) ++hi;
    if (hi - lo > best_count) {
      best_count = hi - lo;
      best = h;
    }
  }
  return best_count >= static_cast<std::size_t>(min_inliers) ? best : 0.0;
}

}  // namespace

std::optional<GroundPlane> fit_ground_plane(const std::vector<Vec3>& points_cam, const GroundPlaneOptions& options,
                                            std::uint64_t seed) {
  const std::vector<std::size_t> candidates = candidates_below(points_cam, options);
  if (candidates.size() < static_cast<std::size_t>(options.min_inliers)) return std::nullopt;
  const double min_cos = std::cos(options.max_tilt_deg * M_PI / 180.0);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, candidates.size() - 1);
  std::size_t best_count = 0;
  Vec3 best_normal = Vec3::UnitY();
  double best_distance = 0;
  for (int it = 0; it < options.iterations; ++it) {
    const Vec3& a = points_cam[candidates[pick(rng)]];
    const Vec3& b = points_cam[candidates[pick(rng)]];
    const Vec3& c = points_cam[candidates[pick(rng)]];
    Vec3 normal = (b - a).cross(c - a);
    const double norm = normal.norm();
    if (!(norm > 1e-12)) continue;
    normal /= norm;
    if (normal.y() < 0) normal = -normal;
    if (normal.y() < min_cos) continue;
    const double distance = normal.dot(a);
    if (!(distance > 0)) continue;
    const std::size_t count = inliers_of(points_cam, candidates, normal, distance, options.inlier_ratio).size();
    if (count > best_count) {
      best_count = count;
      best_normal = normal;
      best_distance = distance;
    }
  }
  if (best_count < static_cast<std::size_t>(options.min_inliers)) return std::nullopt;
  // Least squares on the inliers: the normal is the centred scatter's smallest eigenvector.
  GroundPlane plane;
  plane.inliers = inliers_of(points_cam, candidates, best_normal, best_distance, options.inlier_ratio);
  Vec3 centroid = Vec3::Zero();
  for (std::size_t i : plane.inliers) centroid += points_cam[i];
  centroid /= static_cast<double>(plane.inliers.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (std::size_t i : plane.inliers) scatter += (points_cam[i] - centroid) * (points_cam[i] - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  Vec3 normal = eigen.eigenvectors().col(0).normalized();
  if (normal.y() < 0) normal = -normal;
  const double distance = normal.dot(centroid);
  if (normal.y() < min_cos || !(distance > 0)) {  // the refit left the admissible set: keep the hypothesis
    plane.normal = best_normal;
    plane.distance = best_distance;
  } else {
    plane.normal = normal;
    plane.distance = distance;
    plane.inliers = inliers_of(points_cam, candidates, normal, distance, options.inlier_ratio);
    if (plane.inliers.size() < static_cast<std::size_t>(options.min_inliers)) return std::nullopt;
  }
  return plane;
}

std::optional<Vec3> consensus_normal(const std::vector<Vec3>& normals, double max_angle_deg, int min_support) {
  const double min_cos = std::cos(max_angle_deg * M_PI / 180.0);
  std::size_t best = 0;
  int best_support = 0;
  for (std::size_t i = 0; i < normals.size(); ++i) {
    int support = 0;
    for (const Vec3& other : normals) support += normals[i].dot(other) >= min_cos ? 1 : 0;
    if (support > best_support) {
      best_support = support;
      best = i;
    }
  }
  if (best_support < min_support || normals.empty()) return std::nullopt;
  Vec3 sum = Vec3::Zero();
  for (const Vec3& other : normals) {
    if (normals[best].dot(other) >= min_cos) sum += other;
  }
  return sum.normalized();
}

std::optional<GroundPlane> ground_along_normal(const std::vector<Vec3>& points_cam, const Vec3& normal,
                                               const GroundPlaneOptions& options) {
  const double r = options.inlier_ratio;
  std::vector<std::size_t> candidates = candidates_below(points_cam, options);
  const double first = height_mode(points_cam, candidates, normal, r, options.min_inliers);
  if (!(first > 0)) return std::nullopt;
  // The road under the car: only points within max_lateral_ratio heights to either side (a pavement, a
  // kerb or parked cars beside the lane lie at other heights).
  candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                  [&](std::size_t i) { return std::abs(points_cam[i].x()) > options.max_lateral_ratio * first; }),
                   candidates.end());
  const double best = height_mode(points_cam, candidates, normal, r, options.min_inliers);
  if (!(best > 0)) return std::nullopt;
  GroundPlane plane;
  plane.normal = normal;
  plane.distance = best;
  const std::vector<std::size_t> mode_points = inliers_of(points_cam, candidates, normal, best, r);
  // Least squares on those points; a refined normal that turns too far from the mounting's is not kept.
  Vec3 centroid = Vec3::Zero();
  for (std::size_t i : mode_points) centroid += points_cam[i];
  centroid /= static_cast<double>(mode_points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (std::size_t i : mode_points) scatter += (points_cam[i] - centroid) * (points_cam[i] - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  Vec3 refined = eigen.eigenvectors().col(0).normalized();
  if (refined.dot(normal) < 0) refined = -refined;
  if (refined.dot(normal) >= std::cos(options.max_normal_change_deg * M_PI / 180.0) && refined.dot(centroid) > 0) {
    plane.normal = refined;
    plane.distance = refined.dot(centroid);
  } else {
    plane.distance = normal.dot(centroid);
  }
  plane.inliers = inliers_of(points_cam, candidates, plane.normal, plane.distance, r);
  if (plane.inliers.size() < static_cast<std::size_t>(options.min_inliers)) return std::nullopt;
  return plane;
}

int GroundEstimate::keyframes_with_ground() const {
  return static_cast<int>(std::count_if(planes.begin(), planes.end(), [](const auto& p) { return p.has_value(); }));
}

std::optional<GroundEstimate> estimate_ground(const std::vector<std::vector<Vec3>>& points_per_keyframe,
                                              const GroundPlaneOptions& options) {
  std::vector<Vec3> normals;
  for (std::size_t k = 0; k < points_per_keyframe.size(); ++k) {
    if (auto fit = fit_ground_plane(points_per_keyframe[k], options, k + 1)) normals.push_back(fit->normal);
  }
  const int min_support = std::max(3, static_cast<int>(normals.size()) / 5);
  const auto normal = consensus_normal(normals, options.consensus_deg, min_support);
  if (!normal) return std::nullopt;
  GroundEstimate estimate;
  estimate.normal = *normal;
  std::vector<double> distances;
  for (const auto& points : points_per_keyframe) {
    estimate.planes.push_back(ground_along_normal(points, *normal, options));
    if (estimate.planes.back()) distances.push_back(estimate.planes.back()->distance);
  }
  if (distances.empty()) return std::nullopt;
  const auto mid = distances.begin() + static_cast<std::ptrdiff_t>(distances.size() / 2);
  std::nth_element(distances.begin(), mid, distances.end());
  estimate.height = *mid;
  for (auto& plane : estimate.planes) {
    if (plane && std::abs(plane->distance / estimate.height - 1.0) > options.max_height_change) plane.reset();
  }
  return estimate;
}

}  // namespace crowdslam::geometry
