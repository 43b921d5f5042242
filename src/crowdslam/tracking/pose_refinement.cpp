#include "crowdslam/tracking/pose_refinement.h"

#include "crowdslam/map/map_point.h"

namespace crowdslam::tracking {

int optimize_frame_pose(map::Frame& frame, const optim::PoseOptimizerOptions& options) {
  const auto& f = *frame.features;
  std::vector<optim::PoseObservation> observations;
  std::vector<size_t> slots;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    const auto& p = frame.map_points[i];
    if (!p) continue;
    if (frame.dynamic[i]) {  // known to move: no say in the pose
      frame.outliers[i] = true;
      continue;
    }
    observations.push_back({p->world(), geometry::Vec2(f.keys_un[i].pt.x, f.keys_un[i].pt.y), f.right_u[i],
                            frame.levels->inv_sigma2[f.keys_un[i].octave]});
    slots.push_back(i);
  }
  const auto result = optim::optimize_pose(*frame.camera, *frame.cam_from_world, observations, options);
  if (!result.success) return 0;
  frame.cam_from_world = result.cam_from_world;
  for (size_t k = 0; k < slots.size(); ++k) frame.outliers[slots[k]] = !result.inliers[k];
  return result.num_inliers;
}

int discard_outliers_count_map_points(map::Frame& frame) {
  int in_map = 0;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    auto& p = frame.map_points[i];
    if (!p) continue;
    if (frame.dynamic[i]) continue;  // kept for the dynamic check after the pose; not a tracked point
    if (frame.outliers[i]) {
      p.reset();
      frame.outliers[i] = false;
    } else if (p->num_observations() > 0) {
      ++in_map;
    }
  }
  return in_map;
}

MatchResidual match_residual(const map::Frame& frame, size_t i, const map::MapPoint& point, const geometry::SE3& pose) {
  const auto& f = *frame.features;
  const geometry::PinholeCamera& camera = *frame.camera;
  const bool with_depth = f.has_right(i) && camera.is_stereo();
  MatchResidual r;
  r.threshold = with_depth ? kMatchChi2Stereo : kMatchChi2Mono;
  const geometry::Vec3 in_cam = pose * point.world();
  if (in_cam.z() <= 0) {
    r.chi2 = 1e9;
    return r;
  }
  const geometry::Vec2 pixel = camera.project(in_cam);
  const double du = f.keys_un[i].pt.x - pixel.x();
  const double dv = f.keys_un[i].pt.y - pixel.y();
  double e2 = du * du + dv * dv;
  if (with_depth) {
    const double dr = f.right_u[i] - (pixel.x() - camera.bf / in_cam.z());
    e2 += dr * dr;
  }
  r.chi2 = e2 * frame.levels->inv_sigma2[f.keys_un[i].octave];
  return r;
}

std::shared_ptr<map::MapPoint> point_from_depth(const map::Frame& frame, size_t i) {
  const auto& f = *frame.features;
  const geometry::Vec2 pixel(f.keys_un[i].pt.x, f.keys_un[i].pt.y);
  const geometry::Vec3 world = frame.cam_from_world->inverse() * frame.camera->unproject(pixel, f.depth_m[i]);
  auto point = std::make_shared<map::MapPoint>(0, world, nullptr, frame.id);
  point->set_descriptor(f.descriptor(i));
  return point;
}

}  // namespace crowdslam::tracking
