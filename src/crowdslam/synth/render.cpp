#include "crowdslam/synth/render.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace crowdslam::synth {
namespace {

using V3 = Eigen::Vector3d;
constexpr double kNearM = 0.01;
constexpr double kLodBias = -0.5;  // slightly sharp rather than slightly blurry

// A box prepared for one frame: camera centre in box coordinates, rotation, and the pixel rows/cols its
// projection may cover.
struct PreparedBox {
  const Box* box = nullptr;
  V3 origin_local;
  double cos_yaw = 1.0;
  double sin_yaw = 0.0;
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  // inclusive pixel ranges
};

// Image projections of the part of a box (8 corners) or quad (4 corners) in front of the near plane: the
// corners in front and the points where edges (corners whose indices differ in one bit) cross the near
// plane. Their convex hull is the exact silhouette.
template <size_t N>
std::vector<cv::Point2d> projected_corners(const std::array<V3, N>& corners,
                                           const geometry::SE3& cam_from_world, const Intrinsics& k) {
  std::array<V3, N> cam;
  for (size_t i = 0; i < N; ++i) cam[i] = cam_from_world * corners[i];
  std::vector<cv::Point2d> points;
  const auto add = [&](const V3& p) {
    points.emplace_back(k.fx * p.x() / p.z() + k.cx, k.fy * p.y() / p.z() + k.cy);
  };
  for (const V3& p : cam) {
    if (p.z() >= kNearM) add(p);
  }
  for (size_t a = 0; a < N; ++a) {
    for (size_t bit = 1; bit < N; bit <<= 1) {
      const size_t b = a | bit;
      if (b == a) continue;
      const V3& p = cam[a];
      const V3& q = cam[b];
      if ((p.z() < kNearM) == (q.z() < kNearM)) continue;
      const double s = (kNearM - p.z()) / (q.z() - p.z());
      add(p + s * (q - p));
    }
  }
  return points;
}

std::vector<cv::Point2d> projected_points(const Box& box, const geometry::SE3& cam_from_world,
                                          const Intrinsics& k) {
  return projected_corners(box.corners(), cam_from_world, k);
}

cv::Rect2d bounding(const std::vector<cv::Point2d>& points) {
  double min_x = points[0].x, max_x = points[0].x, min_y = points[0].y, max_y = points[0].y;
  for (const auto& p : points) {
    min_x = std::min(min_x, p.x);
    max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y);
    max_y = std::max(max_y, p.y);
  }
  return {min_x, min_y, max_x - min_x, max_y - min_y};
}

// Unclipped bounds of the part of the box in front of the near plane; nullopt if all of it is behind.
std::optional<cv::Rect2d> raw_bounds(const Box& box, const geometry::SE3& cam_from_world, const Intrinsics& k) {
  const auto points = projected_points(box, cam_from_world, k);
  if (points.empty()) return std::nullopt;
  return bounding(points);
}

// Sutherland-Hodgman: keeps the part of a convex polygon where sign * (coordinate axis) <= sign * limit.
std::vector<cv::Point2d> clip_polygon(const std::vector<cv::Point2d>& polygon, int axis, double limit, double sign) {
  std::vector<cv::Point2d> out;
  const auto inside = [&](const cv::Point2d& p) { return sign * ((axis == 0 ? p.x : p.y) - limit) <= 0.0; };
  for (size_t i = 0; i < polygon.size(); ++i) {
    const cv::Point2d& a = polygon[i];
    const cv::Point2d& b = polygon[(i + 1) % polygon.size()];
    if (inside(a)) out.push_back(a);
    if (inside(a) != inside(b)) {
      const double ca = axis == 0 ? a.x : a.y;
      const double cb = axis == 0 ? b.x : b.y;
      const double s = (limit - ca) / (cb - ca);
      out.push_back(a + s * (b - a));
    }
  }
  return out;
}

// Pixel rows/cols a projection with these (unclipped) bounds may cover, one pixel of margin, clamped to
// [-1, size]; an empty range when there are no bounds.
void set_pixel_range(const std::optional<cv::Rect2d>& bounds, const Intrinsics& k, int& x0, int& x1, int& y0,
                     int& y1) {
  if (!bounds) return;  // empty range
  const auto clamp_px = [](double v, int hi) {
    return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(hi + 1)));
  };
  x0 = clamp_px(std::floor(bounds->x) - 1, k.width);
  x1 = clamp_px(std::ceil(bounds->x + bounds->width) + 1, k.width);
  y0 = clamp_px(std::floor(bounds->y) - 1, k.height);
  y1 = clamp_px(std::ceil(bounds->y + bounds->height) + 1, k.height);
}

PreparedBox prepare(const Box& box, const V3& camera_centre, const geometry::SE3& cam_from_world,
                    const Intrinsics& k) {
  PreparedBox p;
  p.box = &box;
  p.origin_local = box.to_local(camera_centre);
  p.cos_yaw = std::cos(box.yaw);
  p.sin_yaw = std::sin(box.yaw);
  if (box.inside) {
    p.x1 = k.width - 1;
    p.y1 = k.height - 1;
    return p;
  }
  set_pixel_range(raw_bounds(box, cam_from_world, k), k, p.x0, p.x1, p.y0, p.y1);
  return p;
}

// A billboard prepared for one frame: its sprite and the pixel rows/cols its projection may cover.
struct PreparedBillboard {
  const Billboard* billboard = nullptr;
  const Sprite* sprite = nullptr;
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  // inclusive pixel ranges
};

PreparedBillboard prepare(const Billboard& billboard, const Scene& scene,
                          const geometry::SE3& cam_from_world) {
  PreparedBillboard p;
  p.billboard = &billboard;
  assert(billboard.sprite >= 0 && billboard.sprite < static_cast<int>(scene.sprites().size()));
  p.sprite = &scene.sprites()[billboard.sprite];
  const auto points = projected_corners(billboard.corners(), cam_from_world, scene.intrinsics());
  set_pixel_range(points.empty() ? std::nullopt : std::optional<cv::Rect2d>(bounding(points)),
                  scene.intrinsics(), p.x0, p.x1, p.y0, p.y1);
  return p;
}

// The ray of pixel (u, v) in world directions, scaled so that its camera z is 1 (ray parameter = depth).
// One function for the renderer and the footprint, so both see the same bits.
[[gnu::noinline]] V3 pixel_dir(const geometry::Mat3& rotation, const Intrinsics& k, int u, int v) {
  const V3 dir_cam((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
  return rotation * dir_cam;
}

// A ray's hit on a billboard where its sprite is opaque: depth and level-0 texel coordinates.
struct SpriteHit {
  double t = 0.0;
  double s = 0.0;
  double u = 0.0;
};

[[gnu::noinline]] std::optional<SpriteHit> billboard_pixel(const PreparedBillboard& p, const V3& origin,
                                                           const V3& dir) {
  const auto hit = intersect_quad(*p.billboard, origin, dir, kNearM);
  if (!hit) return std::nullopt;
  const double across = p.billboard->mirrored ? 1.0 - hit->across : hit->across;
  const double s = across * p.sprite->alpha.cols - 0.5;
  const double t = hit->down * p.sprite->alpha.rows - 0.5;
  if (!p.sprite->opaque(s, t)) return std::nullopt;
  return SpriteHit{hit->t, s, t};
}

void shade_sprite(const PreparedBillboard& p, const SpriteHit& h, const V3& dir, double ray_scale,
                  double focal, cv::Vec3b& out) {
  const double ray_length = h.t * ray_scale;
  const double cos_incidence = std::max(0.05, std::abs(p.billboard->normal().dot(dir)) / ray_scale);
  const double texels_per_metre = p.sprite->alpha.rows / p.billboard->height_m;
  const double texels_per_pixel = texels_per_metre * ray_length / (focal * std::sqrt(cos_incidence));
  const double lod = std::log2(static_cast<float>(std::max(texels_per_pixel, 1e-6))) + kLodBias;
  const cv::Vec3f c = p.sprite->colour.sample(h.s, h.u, lod);
  for (int ch = 0; ch < 3; ++ch) out[ch] = cv::saturate_cast<uchar>(c[ch]);
}

struct PixelHit {
  const PreparedBox* prepared = nullptr;
  BoxHit hit;
  V3 dir_local;
};

void shade_pixel(const Scene& scene, const PixelHit& h, double ray_scale, double focal, cv::Vec3b& out) {
  const Box& box = *h.prepared->box;
  const V3 local = h.prepared->origin_local + h.hit.t * h.dir_local;
  const Face& face = box.faces[h.hit.face];
  const Eigen::Vector2d uv = face_uv(box, h.hit.face, local);
  const double ray_length = h.hit.t * ray_scale;
  const double cos_incidence = std::max(0.05, std::abs(h.dir_local[h.hit.face / 2]) / ray_scale);
  const double texels_per_pixel = kTexelsPerMetre * ray_length / (focal * std::sqrt(cos_incidence));
  const double lod = std::log2(static_cast<float>(std::max(texels_per_pixel, 1e-6))) + kLodBias;
  const cv::Vec3f c = scene.textures()[face.texture].sample(uv.x() + face.u_offset, uv.y() + face.v_offset, lod);
  for (int ch = 0; ch < 3; ++ch) out[ch] = cv::saturate_cast<uchar>(c[ch] * face.shade);
}

}  // namespace

std::optional<cv::Rect2d> projected_bounds(const Box& box, const geometry::SE3& cam_from_world,
                                           const Intrinsics& k) {
  const auto points = projected_points(box, cam_from_world, k);
  if (points.empty()) return std::nullopt;
  std::vector<cv::Point2f> as_float;
  for (const auto& p : points) as_float.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  std::vector<int> hull_index;
  cv::convexHull(as_float, hull_index);
  std::vector<cv::Point2d> polygon;
  for (int i : hull_index) polygon.push_back(points[i]);
  polygon = clip_polygon(polygon, 0, 0.0, -1.0);
  polygon = clip_polygon(polygon, 0, k.width - 1.0, 1.0);
  polygon = clip_polygon(polygon, 1, 0.0, -1.0);
  polygon = clip_polygon(polygon, 1, k.height - 1.0, 1.0);
  if (polygon.empty()) return std::nullopt;
  const cv::Rect2d r = bounding(polygon);
  const double x0 = std::clamp(r.x, 0.0, k.width - 1.0);
  const double y0 = std::clamp(r.y, 0.0, k.height - 1.0);
  const double x1 = std::clamp(r.x + r.width, x0, k.width - 1.0);
  const double y1 = std::clamp(r.y + r.height, y0, k.height - 1.0);
  return cv::Rect2d(x0, y0, x1 - x0, y1 - y0);
}

RenderedFrame render(const Scene& scene, const geometry::SE3& world_from_cam, const std::vector<Box>& moving,
                     const std::vector<Billboard>& billboards) {
  const Intrinsics& k = scene.intrinsics();
  const geometry::SE3 cam_from_world = world_from_cam.inverse();
  const V3 centre = world_from_cam.translation();
  const geometry::Mat3 rotation = world_from_cam.rotation_matrix();

  std::vector<PreparedBox> boxes;
  for (const Box& b : scene.static_boxes()) boxes.push_back(prepare(b, centre, cam_from_world, k));
  for (const Box& b : moving) boxes.push_back(prepare(b, centre, cam_from_world, k));
  std::vector<PreparedBillboard> quads;
  for (const Billboard& b : billboards) quads.push_back(prepare(b, scene, cam_from_world));

  RenderedFrame frame;
  frame.colour.create(k.height, k.width, CV_8UC3);
  frame.depth_m.create(k.height, k.width, CV_32F);
  frame.person_label.create(k.height, k.width, CV_16U);
  frame.moving.create(k.height, k.width, CV_8U);
  std::vector<const PreparedBox*> row_boxes;
  std::vector<const PreparedBillboard*> row_quads;
  for (int v = 0; v < k.height; ++v) {
    row_boxes.clear();
    for (const auto& p : boxes) {
      if (v >= p.y0 && v <= p.y1 && p.x1 >= p.x0) row_boxes.push_back(&p);
    }
    row_quads.clear();
    for (const auto& p : quads) {
      if (v >= p.y0 && v <= p.y1 && p.x1 >= p.x0) row_quads.push_back(&p);
    }
    auto* colour_row = frame.colour.ptr<cv::Vec3b>(v);
    auto* depth_row = frame.depth_m.ptr<float>(v);
    auto* label_row = frame.person_label.ptr<std::uint16_t>(v);
    auto* moving_row = frame.moving.ptr<std::uint8_t>(v);
    for (int u = 0; u < k.width; ++u) {
      const V3 dir = pixel_dir(rotation, k, u, v);  // camera z = 1: ray parameter = depth
      PixelHit best;
      best.hit.t = std::numeric_limits<double>::infinity();
      for (const PreparedBox* p : row_boxes) {
        if (u < p->x0 || u > p->x1) continue;
        const V3 d(p->cos_yaw * dir.x() + p->sin_yaw * dir.y(), -p->sin_yaw * dir.x() + p->cos_yaw * dir.y(),
                   dir.z());
        const auto hit = intersect_local(*p->box, p->origin_local, d);
        if (hit && hit->t < best.hit.t) best = {p, *hit, d};
      }
      const PreparedBillboard* best_quad = nullptr;
      SpriteHit quad_hit;
      for (const PreparedBillboard* p : row_quads) {
        if (u < p->x0 || u > p->x1) continue;
        const auto hit = billboard_pixel(*p, centre, dir);
        if (hit && hit->t < best.hit.t && (!best_quad || hit->t < quad_hit.t)) {
          best_quad = p;
          quad_hit = *hit;
        }
      }
      if (best_quad) {
        const double ray_scale = V3((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).norm();
        shade_sprite(*best_quad, quad_hit, dir, ray_scale, k.fx, colour_row[u]);
        depth_row[u] = static_cast<float>(quad_hit.t);
        label_row[u] = static_cast<std::uint16_t>(best_quad->billboard->person_id);
        moving_row[u] = 255;
        continue;
      }
      if (!best.prepared) {
        colour_row[u] = cv::Vec3b(0, 0, 0);
        depth_row[u] = 0.0f;
        label_row[u] = 0;
        moving_row[u] = 0;
        continue;
      }
      const V3 dir_cam((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      shade_pixel(scene, best, dir_cam.norm(), k.fx, colour_row[u]);
      depth_row[u] = static_cast<float>(best.hit.t);
      label_row[u] = static_cast<std::uint16_t>(best.prepared->box->person_id);
      moving_row[u] = best.prepared->box->person_id > 0 || best.prepared->box->mover_id > 0 ? 255 : 0;
    }
  }
  return frame;
}

BillboardFootprint billboard_footprint(const Scene& scene, const Billboard& billboard,
                                       const geometry::SE3& world_from_cam) {
  const Intrinsics& k = scene.intrinsics();
  const PreparedBillboard p = prepare(billboard, scene, world_from_cam.inverse());
  const V3 centre = world_from_cam.translation();
  const geometry::Mat3 rotation = world_from_cam.rotation_matrix();
  BillboardFootprint f;
  f.min_u = k.width;
  f.min_v = k.height;
  for (int v = std::max(0, p.y0); v <= std::min(k.height - 1, p.y1); ++v) {
    for (int u = std::max(0, p.x0); u <= std::min(k.width - 1, p.x1); ++u) {
      if (!billboard_pixel(p, centre, pixel_dir(rotation, k, u, v))) continue;
      ++f.pixels;
      f.min_u = std::min(f.min_u, u);
      f.max_u = std::max(f.max_u, u);
      f.min_v = std::min(f.min_v, v);
      f.max_v = std::max(f.max_v, v);
    }
  }
  if (f.pixels == 0) f = BillboardFootprint{};
  f.unbounded_pixels = f.pixels;
  // Beyond the borders: the projection's whole range (at most 4 image sizes out), on a grid of `step`.
  const auto points = projected_corners(billboard.corners(), world_from_cam.inverse(), k);
  if (points.empty()) return f;
  const cv::Rect2d r = bounding(points);
  const int u0 = static_cast<int>(std::max(std::floor(r.x), -4.0 * k.width));
  const int u1 = static_cast<int>(std::min(std::ceil(r.x + r.width), 5.0 * k.width));
  const int v0 = static_cast<int>(std::max(std::floor(r.y), -4.0 * k.height));
  const int v1 = static_cast<int>(std::min(std::ceil(r.y + r.height), 5.0 * k.height));
  const int step = std::max(1, static_cast<int>(std::ceil(std::max(u1 - u0, v1 - v0) / 600.0)));
  for (int v = v0; v <= v1; v += step) {
    for (int u = u0; u <= u1; u += step) {
      if (u >= 0 && u < k.width && v >= 0 && v < k.height) continue;  // counted exactly above
      if (billboard_pixel(p, centre, pixel_dir(rotation, k, u, v))) f.unbounded_pixels += step * step;
    }
  }
  return f;
}

RenderedFrame render_frame(const Scene& scene, int frame, bool right_camera) {
  const geometry::SE3 pose =
      right_camera ? scene.right_world_from_cam(frame) : scene.trajectory().at(frame).world_from_cam;
  return render(scene, pose, scene.moving_boxes(frame), scene.people_billboards(frame));
}

}  // namespace crowdslam::synth
