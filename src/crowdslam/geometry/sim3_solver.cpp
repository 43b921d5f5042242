#include "crowdslam/geometry/sim3_solver.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "crowdslam/geometry/umeyama.h"
#include "crowdslam/util/error.h"

namespace crowdslam::geometry {

void Sim3SolverOptions::check() const {
  auto fail = [](const std::string& key, double value) {
    return InputError("sim3 solver: " + key + " is invalid: " + std::to_string(value));
  };
  if (!(probability > 0.0 && probability < 1.0)) throw fail("probability (must be in (0, 1))", probability);
  if (min_inliers < 3) throw fail("min_inliers (must be >= 3)", min_inliers);
  if (max_iterations < 1) throw fail("max_iterations (must be >= 1)", max_iterations);
  if (!(chi2 > 0.0)) throw fail("chi2 (must be > 0)", chi2);
}

namespace {

bool fits(const PinholeCamera& camera, const Vec3& point_cam, const Eigen::Vector2d& pixel,
          double max_error2) {
  if (!(point_cam.z() > 0.0)) return false;
  return (camera.project(point_cam) - pixel).squaredNorm() < max_error2;
}

// Horn / Umeyama fit of cam1_from_cam2 on the matches with the given indices.
Sim3 fit(const std::vector<Sim3Match>& matches, const std::vector<int>& indices, bool fix_scale) {
  Eigen::Matrix3Xd source(3, indices.size());
  Eigen::Matrix3Xd target(3, indices.size());
  for (std::size_t i = 0; i < indices.size(); ++i) {
    source.col(i) = matches[indices[i]].point_in_cam2;
    target.col(i) = matches[indices[i]].point_in_cam1;
  }
  const Similarity s = align_umeyama(source, target, !fix_scale);
  return Sim3(s.rotation, s.translation, s.scale);
}

// Three points (nearly) on a line do not fix the rotation about that line.
bool degenerate(const std::vector<Sim3Match>& matches, const std::vector<int>& sample) {
  const Vec3& a = matches[sample[0]].point_in_cam2;
  const Vec3 ab = matches[sample[1]].point_in_cam2 - a;
  const Vec3 ac = matches[sample[2]].point_in_cam2 - a;
  const double scale2 = std::max(ab.squaredNorm(), ac.squaredNorm());
  return !(ab.cross(ac).squaredNorm() > 1e-8 * scale2 * scale2);
}

// Samples needed to draw one all-inlier triple with the given probability.
int required_iterations(double inlier_ratio, double probability, int max_iterations) {
  const double all_inlier = inlier_ratio * inlier_ratio * inlier_ratio;
  if (all_inlier >= 1.0) return 1;
  if (all_inlier <= 0.0) return max_iterations;
  const double n = std::ceil(std::log(1.0 - probability) / std::log(1.0 - all_inlier));
  return n < max_iterations ? std::max(1, static_cast<int>(n)) : max_iterations;
}

std::vector<int> indices_of(const std::vector<bool>& flags) {
  std::vector<int> indices;
  for (std::size_t i = 0; i < flags.size(); ++i) {
    if (flags[i]) indices.push_back(static_cast<int>(i));
  }
  return indices;
}

}  // namespace

int sim3_inliers(const PinholeCamera& camera1, const PinholeCamera& camera2,
                 const std::vector<Sim3Match>& matches, const Sim3& cam1_from_cam2, double chi2,
                 std::vector<bool>& inliers) {
  const Sim3 cam2_from_cam1 = cam1_from_cam2.inverse();
  inliers.assign(matches.size(), false);
  int count = 0;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    const Sim3Match& m = matches[i];
    inliers[i] = fits(camera1, cam1_from_cam2 * m.point_in_cam2, m.pixel1, chi2 * m.sigma2_1) &&
                 fits(camera2, cam2_from_cam1 * m.point_in_cam1, m.pixel2, chi2 * m.sigma2_2);
    count += inliers[i] ? 1 : 0;
  }
  return count;
}

std::optional<Sim3Result> solve_sim3_ransac(const PinholeCamera& camera1, const PinholeCamera& camera2,
                                            const std::vector<Sim3Match>& matches,
                                            const Sim3SolverOptions& options) {
  const int n = static_cast<int>(matches.size());
  if (n < 3 || n < options.min_inliers) return std::nullopt;

  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  Sim3Result best;
  std::vector<bool> flags;
  std::vector<int> sample(3);
  int needed = options.max_iterations;
  int iterations = 0;
  while (iterations < needed) {
    ++iterations;
    sample[0] = pick(rng);
    do sample[1] = pick(rng);
    while (sample[1] == sample[0]);
    do sample[2] = pick(rng);
    while (sample[2] == sample[0] || sample[2] == sample[1]);
    if (degenerate(matches, sample)) continue;

    const Sim3 model = fit(matches, sample, options.fix_scale);
    const int count = sim3_inliers(camera1, camera2, matches, model, options.chi2, flags);
    if (count > best.num_inliers) {
      best.cam1_from_cam2 = model;
      best.inliers = flags;
      best.num_inliers = count;
      needed =
          required_iterations(static_cast<double>(count) / n, options.probability, options.max_iterations);
    }
  }
  best.iterations = iterations;
  if (best.num_inliers < std::max(options.min_inliers, 3)) return std::nullopt;

  // Refit on all inliers while that keeps (or grows) the inlier set.
  for (int round = 0; round < 3; ++round) {
    const Sim3 model = fit(matches, indices_of(best.inliers), options.fix_scale);
    const int count = sim3_inliers(camera1, camera2, matches, model, options.chi2, flags);
    if (count < best.num_inliers) break;
    const bool same_set = flags == best.inliers;
    best.cam1_from_cam2 = model;
    best.inliers = flags;
    best.num_inliers = count;
    if (same_set) break;
  }
  return best;
}

}  // namespace crowdslam::geometry
