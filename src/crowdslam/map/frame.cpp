#include "crowdslam/map/frame.h"

#include "crowdslam/map/map_point.h"

namespace crowdslam::map {

Frame::Frame(uint64_t id_in, double timestamp_s_in, std::shared_ptr<const geometry::PinholeCamera> camera_in,
             std::shared_ptr<const ScaleLevels> levels_in, std::shared_ptr<const FrameFeatures> features_in)
    : id(id_in),
      timestamp_s(timestamp_s_in),
      camera(std::move(camera_in)),
      levels(std::move(levels_in)),
      features(std::move(features_in)),
      map_points(features->size()),
      outliers(features->size(), false),
      dynamic(features->size(), false),
      motion_history(features->size(), 0),
      in_box(features->size(), false) {}

std::optional<PointProjection> Frame::project(const MapPoint& point, double min_view_cos) const {
  const MapPoint::ViewGeometry view = point.view_geometry();
  const geometry::Vec3& world = view.world;
  const geometry::Vec3 in_cam = *cam_from_world * world;
  if (in_cam.z() <= 0) return std::nullopt;
  const geometry::Vec2 pixel = camera->project(in_cam);
  if (!features->grid.bounds().contains(pixel)) return std::nullopt;

  const geometry::Vec3 ray = world - camera_center();
  const double distance = ray.norm();
  if (distance < view.min_distance || distance > view.max_distance) return std::nullopt;
  const double view_cos = ray.dot(view.normal) / distance;
  if (view_cos < min_view_cos) return std::nullopt;

  PointProjection p;
  p.u = pixel.x();
  p.v = pixel.y();
  p.right_u = camera->is_stereo() ? pixel.x() - camera->bf / in_cam.z() : -1.0;
  p.distance = distance;
  p.view_cos = view_cos;
  p.predicted_level = view.predict_scale(static_cast<float>(distance), *levels);
  return p;
}

int Frame::num_tracked() const {
  int count = 0;
  for (size_t i = 0; i < map_points.size(); ++i) {
    if (map_points[i] && !outliers[i] && !map_points[i]->is_bad()) ++count;
  }
  return count;
}

int Frame::discard_outliers() {
  int kept = 0;
  for (size_t i = 0; i < map_points.size(); ++i) {
    if (!map_points[i]) continue;
    if (outliers[i]) {
      map_points[i].reset();
      outliers[i] = false;
    } else {
      ++kept;
    }
  }
  return kept;
}

}  // namespace crowdslam::map
