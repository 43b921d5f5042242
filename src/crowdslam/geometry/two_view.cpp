#include "crowdslam/geometry/two_view.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <random>

#include "crowdslam/geometry/triangulation.h"
#include "crowdslam/util/error.h"

namespace crowdslam::geometry {

namespace {

constexpr int kSampleSize = 8;
constexpr double kCosLowParallax = 0.99998;  // about 0.36 degrees
constexpr size_t kParallaxRank = 50;         // parallax reported: that of the 50th-best good point
constexpr double kPi = 3.14159265358979323846;

// Hartley normalisation: centroid to the origin, mean distance sqrt(2).
struct Normalized {
  std::vector<Vec2> points;
  Mat3 transform = Mat3::Identity();  // normalized = transform * pixel
};

Normalized normalize_points(const std::vector<Vec2>& points) {
  Normalized out;
  Vec2 centroid = Vec2::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  double mean_distance = 0.0;
  for (const auto& p : points) mean_distance += (p - centroid).norm();
  mean_distance /= static_cast<double>(points.size());
  const double s = mean_distance > 0.0 ? std::sqrt(2.0) / mean_distance : 1.0;
  out.points.reserve(points.size());
  for (const auto& p : points) out.points.emplace_back(s * (p - centroid));
  out.transform << s, 0, -s * centroid.x(), 0, s, -s * centroid.y(), 0, 0, 1;
  return out;
}

// Right singular vector of the smallest singular value of an n x 9 system, as a 3x3 row-major matrix.
Mat3 null_vector_3x3(const Eigen::Matrix<double, Eigen::Dynamic, 9>& a) {
  // A^T A is 9x9 whatever n is; its eigenvector of the smallest eigenvalue is the null vector. The SVD
  // of A itself is used for accuracy (n is small in RANSAC, the refinement is done once).
  const Eigen::JacobiSVD<Eigen::Matrix<double, Eigen::Dynamic, 9>> svd(a, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 9, 1> h = svd.matrixV().col(8);
  Mat3 m;
  m << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  return m;
}

Mat3 unit_frobenius(const Mat3& m) {
  const double n = m.norm();
  return n > 0.0 ? Mat3(m / n) : m;
}

std::vector<Vec2> gather(const std::vector<Vec2>& points, const std::vector<size_t>& indices) {
  std::vector<Vec2> out;
  out.reserve(indices.size());
  for (size_t i : indices) out.push_back(points[i]);
  return out;
}

std::vector<size_t> inlier_indices(const ModelScore& score) {
  std::vector<size_t> out;
  for (size_t i = 0; i < score.inliers.size(); ++i) {
    if (score.inliers[i]) out.push_back(i);
  }
  return out;
}

// Squared pixel distance of x2 to the epipolar line F x1.
double line_distance_squared(const Mat3& f, const Vec2& x1, const Vec2& x2) {
  const Vec3 line = f * Vec3(x1.x(), x1.y(), 1.0);
  const double norm2 = line.x() * line.x() + line.y() * line.y();
  if (norm2 <= 0.0) return std::numeric_limits<double>::infinity();
  const double d = line.x() * x2.x() + line.y() * x2.y() + line.z();
  return d * d / norm2;
}

double transfer_error_squared(const Mat3& h, const Vec2& from, const Vec2& to) {
  const Vec3 mapped = h * Vec3(from.x(), from.y(), 1.0);
  if (std::abs(mapped.z()) < 1e-12) return std::numeric_limits<double>::infinity();
  return (mapped.hnormalized() - to).squaredNorm();
}

// Sampson distance (pixels) of a correspondence to the epipolar geometry F.
double sampson_distance(const Mat3& f, const Vec2& x1, const Vec2& x2) {
  const Vec3 h1(x1.x(), x1.y(), 1.0);
  const Vec3 h2(x2.x(), x2.y(), 1.0);
  const Vec3 f1 = f * h1;
  const Vec3 f2 = f.transpose() * h2;
  const double den = f1.x() * f1.x() + f1.y() * f1.y() + f2.x() * f2.x() + f2.y() * f2.y();
  return den > 0.0 ? h2.dot(f1) / std::sqrt(den) : 0.0;
}

// F of a relative pose seen by camera K (K^-1 given).
Mat3 fundamental_of(const SE3& cam2_from_cam1, const Mat3& k_inv) {
  return k_inv.transpose() * skew(cam2_from_cam1.translation()) * cam2_from_cam1.rotation_matrix() * k_inv;
}

// Levenberg-Marquardt over the five degrees of freedom of an essential matrix (rotation increment and
// translation direction) minimising the Sampson distances of the inliers. The 8-point solution minimises
// an algebraic error only; this brings its pose to the accuracy of the data.
Mat3 refine_fundamental(const Mat3& fundamental_21, const Mat3& k, const std::vector<Vec2>& points1,
                        const std::vector<Vec2>& points2, const std::vector<bool>& inliers) {
  constexpr int kIterations = 15;
  std::vector<size_t> used;
  for (size_t i = 0; i < inliers.size(); ++i) {
    if (inliers[i]) used.push_back(i);
  }
  if (used.size() < static_cast<size_t>(kSampleSize)) return fundamental_21;
  const Mat3 k_inv = k.inverse();
  SE3 pose = poses_from_essential(k.transpose() * fundamental_21 * k).front();
  const auto residuals = [&](const SE3& p, Eigen::VectorXd& r) {
    const Mat3 f = fundamental_of(p, k_inv);
    r.resize(static_cast<Eigen::Index>(used.size()));
    for (size_t j = 0; j < used.size(); ++j) {
      r(static_cast<Eigen::Index>(j)) = sampson_distance(f, points1[used[j]], points2[used[j]]);
    }
  };
  // Perturbation: rotation by so3_exp(w) on the left, translation direction moved in its tangent plane.
  const auto perturbed = [](const SE3& p, const Eigen::Matrix<double, 5, 1>& d) {
    const Vec3 t = p.translation();
    Vec3 b1 = t.unitOrthogonal();
    const Vec3 b2 = t.cross(b1).normalized();
    const Vec3 t_new = (t + d(3) * b1 + d(4) * b2).normalized();
    return SE3(Mat3(so3_exp(d.head<3>()) * p.rotation_matrix()), t_new);
  };
  Eigen::VectorXd r;
  residuals(pose, r);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  Eigen::MatrixXd jacobian(r.size(), 5);
  Eigen::VectorXd r_step;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    constexpr double kStep = 1e-7;
    for (int c = 0; c < 5; ++c) {
      Eigen::Matrix<double, 5, 1> d = Eigen::Matrix<double, 5, 1>::Zero();
      d(c) = kStep;
      residuals(perturbed(pose, d), r_step);
      jacobian.col(c) = (r_step - r) / kStep;
    }
    const Eigen::Matrix<double, 5, 5> jtj = jacobian.transpose() * jacobian;
    const Eigen::Matrix<double, 5, 1> jtr = jacobian.transpose() * r;
    bool improved = false;
    for (int attempt = 0; attempt < 10 && !improved; ++attempt) {
      Eigen::Matrix<double, 5, 5> a = jtj;
      a.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-9);
      const Eigen::Matrix<double, 5, 1> delta = a.ldlt().solve(-jtr);
      if (!delta.allFinite()) break;
      const SE3 candidate = perturbed(pose, delta);
      residuals(candidate, r_step);
      const double candidate_cost = r_step.squaredNorm();
      if (candidate_cost < cost) {
        pose = candidate;
        r = r_step;
        const double gain = cost - candidate_cost;
        cost = candidate_cost;
        lambda = std::max(1e-9, lambda * 0.3);
        improved = true;
        if (gain < 1e-10 * cost) iteration = kIterations;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return unit_frobenius(fundamental_of(pose, k_inv));
}

}  // namespace

const char* to_string(TwoViewModel model) {
  return model == TwoViewModel::kHomography ? "homography" : "fundamental";
}

void TwoViewOptions::check() const {
  if (!(sigma_px > 0)) throw InputError("two-view: sigma_px must be > 0, got " + std::to_string(sigma_px));
  if (ransac_iterations < 1) throw InputError("two-view: ransac_iterations must be >= 1");
  if (!(homography_ratio_threshold > 0 && homography_ratio_threshold < 1)) {
    throw InputError("two-view: homography_ratio_threshold must be in (0, 1)");
  }
  if (!(min_parallax_deg >= 0 && min_parallax_deg < 90))
    throw InputError("two-view: min_parallax_deg in [0, 90)");
  if (min_triangulated < 1) throw InputError("two-view: min_triangulated must be >= 1");
  if (!(min_good_fraction >= 0 && min_good_fraction <= 1))
    throw InputError("two-view: min_good_fraction in [0, 1]");
  if (!(clear_winner_ratio > 0 && clear_winner_ratio < 1))
    throw InputError("two-view: clear_winner_ratio in (0, 1)");
}

Mat3 homography_dlt(const std::vector<Vec2>& points1, const std::vector<Vec2>& points2) {
  assert(points1.size() == points2.size() && points1.size() >= 4);
  const Normalized n1 = normalize_points(points1);
  const Normalized n2 = normalize_points(points2);
  Eigen::Matrix<double, Eigen::Dynamic, 9> a(2 * static_cast<Eigen::Index>(points1.size()), 9);
  for (size_t i = 0; i < points1.size(); ++i) {
    const double u1 = n1.points[i].x(), v1 = n1.points[i].y();
    const double u2 = n2.points[i].x(), v2 = n2.points[i].y();
    const auto r = static_cast<Eigen::Index>(2 * i);
    a.row(r) << 0, 0, 0, -u1, -v1, -1, v2 * u1, v2 * v1, v2;
    a.row(r + 1) << u1, v1, 1, 0, 0, 0, -u2 * u1, -u2 * v1, -u2;
  }
  const Mat3 hn = null_vector_3x3(a);
  return unit_frobenius(n2.transform.inverse() * hn * n1.transform);
}

Mat3 fundamental_eight_point(const std::vector<Vec2>& points1, const std::vector<Vec2>& points2) {
  assert(points1.size() == points2.size() && points1.size() >= 8);
  const Normalized n1 = normalize_points(points1);
  const Normalized n2 = normalize_points(points2);
  Eigen::Matrix<double, Eigen::Dynamic, 9> a(static_cast<Eigen::Index>(points1.size()), 9);
  for (size_t i = 0; i < points1.size(); ++i) {
    const double u1 = n1.points[i].x(), v1 = n1.points[i].y();
    const double u2 = n2.points[i].x(), v2 = n2.points[i].y();
    a.row(static_cast<Eigen::Index>(i)) << u2 * u1, u2 * v1, u2, v2 * u1, v2 * v1, v2, u1, v1, 1;
  }
  const Mat3 fn = null_vector_3x3(a);
  // Rank 2: zero the smallest singular value.
  const Eigen::JacobiSVD<Mat3> svd(fn, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Vec3 s = svd.singularValues();
  s(2) = 0.0;
  const Mat3 f2 = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  return unit_frobenius(n2.transform.transpose() * f2 * n1.transform);
}

namespace {
// ORB-SLAM's two-way model score: each direction's chi2 (error^2 / sigma^2) adds kChi2Mono - chi2 to the
// score when below `inlier_chi2`; a match is an inlier when both directions are.
template <typename ErrorIn2, typename ErrorIn1>
void score_both_ways(ModelScore& out, const std::vector<Vec2>& points1, const std::vector<Vec2>& points2,
                     double sigma_px, double inlier_chi2, ErrorIn2 error_in_2, ErrorIn1 error_in_1) {
  const double inv_sigma2 = 1.0 / (sigma_px * sigma_px);
  for (size_t i = 0; i < points1.size(); ++i) {
    bool inlier = true;
    for (const double chi2 : {error_in_2(points1[i], points2[i]) * inv_sigma2,
                              error_in_1(points2[i], points1[i]) * inv_sigma2}) {
      if (chi2 > inlier_chi2) {
        inlier = false;
      } else {
        out.score += kChi2Mono - chi2;
      }
    }
    out.inliers[i] = inlier;
    if (inlier) ++out.num_inliers;
  }
}
}  // namespace

ModelScore score_homography(const Mat3& homography_21, const std::vector<Vec2>& points1,
                            const std::vector<Vec2>& points2, double sigma_px) {
  ModelScore out;
  out.inliers.assign(points1.size(), false);
  const Mat3 homography_12 = homography_21.inverse();
  if (!homography_12.allFinite()) return out;
  score_both_ways(out, points1, points2, sigma_px, kChi2Mono,
                  [&](const Vec2& a, const Vec2& b) { return transfer_error_squared(homography_21, a, b); },
                  [&](const Vec2& b, const Vec2& a) { return transfer_error_squared(homography_12, b, a); });
  return out;
}

ModelScore score_fundamental(const Mat3& fundamental_21, const std::vector<Vec2>& points1,
                             const std::vector<Vec2>& points2, double sigma_px) {
  ModelScore out;
  out.inliers.assign(points1.size(), false);
  const Mat3 fundamental_12 = fundamental_21.transpose();
  // Same score per unit error as the homography (kChi2Mono), inlier threshold of a 1-DoF residual.
  score_both_ways(out, points1, points2, sigma_px, kChi2OneDof,
                  [&](const Vec2& a, const Vec2& b) { return line_distance_squared(fundamental_21, a, b); },
                  [&](const Vec2& b, const Vec2& a) { return line_distance_squared(fundamental_12, b, a); });
  return out;
}

TwoViewModels estimate_two_view_models(const std::vector<Vec2>& points1, const std::vector<Vec2>& points2,
                                       const TwoViewOptions& options) {
  assert(points1.size() == points2.size() && points1.size() >= static_cast<size_t>(kSampleSize));
  const size_t n = points1.size();
  TwoViewModels out;
  out.homography.score = -1.0;
  out.fundamental.score = -1.0;
  std::mt19937_64 rng(options.seed);
  std::vector<size_t> indices(n);
  std::iota(indices.begin(), indices.end(), 0);
  std::vector<size_t> sample(kSampleSize);
  for (int iteration = 0; iteration < options.ransac_iterations; ++iteration) {
    // Partial Fisher-Yates: 8 distinct indices; the same set feeds both models.
    for (int k = 0; k < kSampleSize; ++k) {
      std::uniform_int_distribution<size_t> pick(static_cast<size_t>(k), n - 1);
      std::swap(indices[static_cast<size_t>(k)], indices[pick(rng)]);
      sample[static_cast<size_t>(k)] = indices[static_cast<size_t>(k)];
    }
    const auto s1 = gather(points1, sample);
    const auto s2 = gather(points2, sample);
    const Mat3 h = homography_dlt(s1, s2);
    ModelScore h_score = score_homography(h, points1, points2, options.sigma_px);
    if (h_score.score > out.homography.score) {
      out.homography_21 = h;
      out.homography = std::move(h_score);
    }
    const Mat3 f = fundamental_eight_point(s1, s2);
    ModelScore f_score = score_fundamental(f, points1, points2, options.sigma_px);
    if (f_score.score > out.fundamental.score) {
      out.fundamental_21 = f;
      out.fundamental = std::move(f_score);
    }
  }
  // Refinement of each model on all its inliers (kept only if it scores better).
  const auto h_inliers = inlier_indices(out.homography);
  if (h_inliers.size() >= static_cast<size_t>(kSampleSize)) {
    const Mat3 h = homography_dlt(gather(points1, h_inliers), gather(points2, h_inliers));
    ModelScore score = score_homography(h, points1, points2, options.sigma_px);
    if (score.score > out.homography.score) {
      out.homography_21 = h;
      out.homography = std::move(score);
    }
  }
  const auto f_inliers = inlier_indices(out.fundamental);
  if (f_inliers.size() >= static_cast<size_t>(kSampleSize)) {
    const Mat3 f = fundamental_eight_point(gather(points1, f_inliers), gather(points2, f_inliers));
    ModelScore score = score_fundamental(f, points1, points2, options.sigma_px);
    if (score.score > out.fundamental.score) {
      out.fundamental_21 = f;
      out.fundamental = std::move(score);
    }
  }
  out.homography.score = std::max(0.0, out.homography.score);
  out.fundamental.score = std::max(0.0, out.fundamental.score);
  const double total = out.homography.score + out.fundamental.score;
  out.homography_ratio = total > 0.0 ? out.homography.score / total : 0.0;
  out.selected = out.homography_ratio > options.homography_ratio_threshold ? TwoViewModel::kHomography
                                                                           : TwoViewModel::kFundamental;
  return out;
}

std::vector<SE3> poses_from_essential(const Mat3& essential) {
  const Eigen::JacobiSVD<Mat3> svd(essential, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 u = svd.matrixU();
  Mat3 v = svd.matrixV();
  if (u.determinant() < 0) u = -u;
  if (v.determinant() < 0) v = -v;
  Mat3 w;
  w << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Mat3 r1 = u * w * v.transpose();
  const Mat3 r2 = u * w.transpose() * v.transpose();
  const Vec3 t = u.col(2).normalized();
  return {SE3(r1, t), SE3(r1, -t), SE3(r2, t), SE3(r2, -t)};
}

std::vector<SE3> poses_from_homography(const Mat3& homography_21, const Mat3& intrinsics) {
  cv::Mat h_cv;
  cv::Mat k_cv;
  cv::eigen2cv(homography_21, h_cv);
  cv::eigen2cv(intrinsics, k_cv);
  std::vector<cv::Mat> rotations;
  std::vector<cv::Mat> translations;
  std::vector<cv::Mat> normals;
  cv::decomposeHomographyMat(h_cv, k_cv, rotations, translations, normals);
  std::vector<SE3> out;
  for (size_t i = 0; i < rotations.size(); ++i) {
    Mat3 r;
    Vec3 t;
    cv::cv2eigen(rotations[i], r);
    cv::cv2eigen(translations[i], t);
    if (!r.allFinite() || !t.allFinite()) continue;
    const double norm = t.norm();
    out.emplace_back(r, norm > 1e-12 ? Vec3(t / norm) : Vec3::Zero());
  }
  return out;
}

PoseCheck check_relative_pose(const SE3& cam2_from_cam1, const PinholeCamera& camera,
                              const std::vector<Vec2>& points1, const std::vector<Vec2>& points2,
                              const std::vector<bool>& use, double sigma_px) {
  PoseCheck out;
  const size_t n = points1.size();
  out.points_cam1.assign(n, Vec3::Zero());
  out.triangulated.assign(n, false);
  const double max_error2 = 4.0 * sigma_px * sigma_px;
  const Vec3 centre2 = cam2_from_cam1.inverse().translation();
  const SE3 identity;
  std::vector<double> cos_parallax;
  cos_parallax.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!use[i]) continue;
    const auto point = triangulate_normalized(identity, camera.normalize(points1[i]), cam2_from_cam1,
                                              camera.normalize(points2[i]));
    if (!point) continue;
    const double cos_p = point_parallax_cosine(*point, Vec3::Zero(), centre2);
    const bool low_parallax = cos_p >= kCosLowParallax;
    const Vec3 in2 = cam2_from_cam1 * *point;
    const bool in_front = point->z() > 0 && in2.z() > 0;
    // A point behind a camera refutes the hypothesis unless it has no parallax (then its depth sign is
    // noise).
    if (!in_front && !low_parallax) continue;
    if ((camera.project(*point) - points1[i]).squaredNorm() > max_error2) continue;
    if ((camera.project(in2) - points2[i]).squaredNorm() > max_error2) continue;
    ++out.num_good;
    cos_parallax.push_back(cos_p);
    if (in_front && !low_parallax) {
      out.triangulated[i] = true;
      out.points_cam1[i] = *point;
    }
  }
  if (!cos_parallax.empty()) {
    std::sort(cos_parallax.begin(), cos_parallax.end());  // ascending cosine = descending angle
    const double c = cos_parallax[std::min(kParallaxRank, cos_parallax.size() - 1)];
    out.parallax_deg = std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kPi;
  }
  return out;
}

bool agrees_with_prior(const SE3& cam2_from_cam1, const TwoViewPrior& prior) {
  constexpr double kDeg = 180.0 / kPi;
  const Mat3 predicted_rotation = prior.cam2_from_cam1.rotation_matrix();
  const double prior_angle = rotation_angle(predicted_rotation) * kDeg;
  const double rotation_error =
      rotation_angle(cam2_from_cam1.rotation_matrix() * predicted_rotation.transpose()) * kDeg;
  if (rotation_error > prior.max_rotation_deg + prior.rotation_share * prior_angle) return false;
  if (!prior.check_direction) return true;
  // The direction of travel: the second camera's centre in the first camera's frame.
  const Vec3 travel = -(cam2_from_cam1.rotation().inverse() * cam2_from_cam1.translation());
  const Vec3 predicted = -(prior.cam2_from_cam1.rotation().inverse() * prior.cam2_from_cam1.translation());
  if (travel.norm() == 0 || predicted.norm() == 0) return false;
  const double cosine = std::clamp(travel.normalized().dot(predicted.normalized()), -1.0, 1.0);
  return std::acos(cosine) * kDeg <= prior.max_direction_deg;
}

std::optional<TwoViewReconstruction> choose_hypothesis(
    const std::vector<SE3>& candidates, const PinholeCamera& camera, const std::vector<Vec2>& points1,
    const std::vector<Vec2>& points2, const ModelScore& model, const TwoViewOptions& options,
    const TwoViewPrior* prior) {
  if (candidates.empty()) return std::nullopt;
  std::vector<PoseCheck> checks;
  checks.reserve(candidates.size());
  size_t best = 0;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (prior && !agrees_with_prior(candidates[i], *prior)) {
      checks.emplace_back();  // takes no part: no good points
    } else {
      checks.push_back(
          check_relative_pose(candidates[i], camera, points1, points2, model.inliers, options.sigma_px));
    }
    if (checks[i].num_good > checks[best].num_good) best = i;
  }
  const int best_good = checks[best].num_good;
  const double min_good =
      std::max(options.min_good_fraction * model.num_inliers, static_cast<double>(options.min_triangulated));
  if (best_good < min_good) return std::nullopt;
  int similar = 0;
  for (const auto& c : checks) {
    if (c.num_good > options.clear_winner_ratio * best_good) ++similar;
  }
  if (similar > 1) return std::nullopt;
  if (checks[best].parallax_deg <= options.min_parallax_deg) return std::nullopt;
  TwoViewReconstruction out;
  out.cam2_from_cam1 = candidates[best];
  out.points_cam1 = std::move(checks[best].points_cam1);
  out.triangulated = std::move(checks[best].triangulated);
  out.num_triangulated = static_cast<int>(std::count(out.triangulated.begin(), out.triangulated.end(), true));
  out.parallax_deg = checks[best].parallax_deg;
  if (out.num_triangulated < options.min_triangulated) return std::nullopt;
  return out;
}

std::optional<TwoViewReconstruction> reconstruct_two_view(const PinholeCamera& camera,
                                                          const std::vector<Vec2>& points1,
                                                          const std::vector<Vec2>& points2,
                                                          const TwoViewOptions& options,
                                                          TwoViewModels* models, const TwoViewPrior* prior) {
  if (points1.size() != points2.size() || points1.size() < static_cast<size_t>(kSampleSize))
    return std::nullopt;
  TwoViewModels estimated = estimate_two_view_models(points1, points2, options);
  const Mat3 k = camera.intrinsic_matrix();
  const auto from_homography = [&] {
    return choose_hypothesis(poses_from_homography(estimated.homography_21, k), camera, points1, points2,
                             estimated.homography, options, prior);
  };
  bool refined_fundamental = false;
  const auto from_fundamental = [&] {
    if (!refined_fundamental) {  // non-linear refinement of F on its inliers, kept when it scores as well
      refined_fundamental = true;
      const Mat3 refined =
          refine_fundamental(estimated.fundamental_21, k, points1, points2, estimated.fundamental.inliers);
      ModelScore refined_score = score_fundamental(refined, points1, points2, options.sigma_px);
      if (refined_score.score >= estimated.fundamental.score) {
        estimated.fundamental_21 = refined;
        estimated.fundamental = std::move(refined_score);
      }
    }
    const Mat3 essential = k.transpose() * estimated.fundamental_21 * k;
    return choose_hypothesis(poses_from_essential(essential), camera, points1, points2, estimated.fundamental,
                             options, prior);
  };
  const bool homography = estimated.selected == TwoViewModel::kHomography;
  std::optional<TwoViewReconstruction> out = homography ? from_homography() : from_fundamental();
  TwoViewModel model = estimated.selected;
  if (!out && prior) {  // the prior can vouch for the other model's hypothesis (step 5)
    out = homography ? from_fundamental() : from_homography();
    model = homography ? TwoViewModel::kFundamental : TwoViewModel::kHomography;
  }
  if (out) out->model = model;
  if (models) *models = std::move(estimated);
  return out;
}

}  // namespace crowdslam::geometry
