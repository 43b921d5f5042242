#include "crowdslam/mapdb/map_export.h"

#include <cstdio>
#include <cstring>
#include <sstream>
#include <vector>

#include "crowdslam/geometry/se3.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/sqlite.h"
#include "crowdslam/util/atomic_file.h"

namespace crowdslam::mapdb {

namespace {
void append(std::string& out, const void* data, size_t bytes) { out.append(static_cast<const char*>(data), bytes); }

Database open_map(const std::filesystem::path& map_file) {
  read_map_header(map_file);  // validates the file (integrity, schema, tables)
  return Database(map_file.string(), Database::Mode::kReadOnly);
}

std::string ply_header(size_t n, bool with_observations) {
  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\ncomment crowdslam map export\nelement vertex " << n
    << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (with_observations) h << "property uint observations\n";
  h << "end_header\n";
  return h.str();
}
}  // namespace

size_t export_points_ply(const std::filesystem::path& map_file, const std::filesystem::path& ply) {
  Database db = open_map(map_file);
  auto st = db.prepare(
      "SELECT p.x, p.y, p.z, (SELECT COUNT(*) FROM observations o WHERE o.point_id = p.id) FROM map_points p "
      "ORDER BY p.id");
  std::string body;
  size_t n = 0;
  while (st.step()) {
    const float xyz[3] = {static_cast<float>(st.real(0)), static_cast<float>(st.real(1)), static_cast<float>(st.real(2))};
    const auto observations = static_cast<uint32_t>(st.integer(3));
    append(body, xyz, sizeof(xyz));
    append(body, &observations, sizeof(observations));
    ++n;
  }
  write_file_atomic(ply, ply_header(n, true) + body);
  return n;
}

size_t export_keyframes_ply(const std::filesystem::path& map_file, const std::filesystem::path& ply) {
  Database db = open_map(map_file);
  auto st = db.prepare("SELECT qx, qy, qz, qw, tx, ty, tz FROM keyframes ORDER BY id");
  std::string body;
  size_t n = 0;
  while (st.step()) {
    const Eigen::Quaterniond q(st.real(3), st.real(0), st.real(1), st.real(2));
    const geometry::SE3 cam_from_world(q, geometry::Vec3(st.real(4), st.real(5), st.real(6)));
    const geometry::Vec3 c = cam_from_world.inverse().translation();
    const float xyz[3] = {static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())};
    append(body, xyz, sizeof(xyz));
    ++n;
  }
  write_file_atomic(ply, ply_header(n, false) + body);
  return n;
}

size_t export_keyframe_trajectory(const std::filesystem::path& map_file, const std::filesystem::path& tum) {
  Database db = open_map(map_file);
  auto st = db.prepare("SELECT timestamp, qx, qy, qz, qw, tx, ty, tz FROM keyframes ORDER BY timestamp, id");
  std::string out = "# timestamp tx ty tz qx qy qz qw (world_from_cam of each keyframe)\n";
  size_t n = 0;
  char line[256];
  while (st.step()) {
    const Eigen::Quaterniond q(st.real(4), st.real(1), st.real(2), st.real(3));
    const geometry::SE3 world_from_cam =
        geometry::SE3(q, geometry::Vec3(st.real(5), st.real(6), st.real(7))).inverse();
    const auto& t = world_from_cam.translation();
    const auto& r = world_from_cam.rotation();
    std::snprintf(line, sizeof(line), "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", st.real(0), t.x(), t.y(), t.z(),
                  r.x(), r.y(), r.z(), r.w());
    out += line;
    ++n;
  }
  write_file_atomic(tum, out);
  return n;
}

}  // namespace crowdslam::mapdb

namespace crowdslam::mapdb {

MapContents read_map_contents(const std::filesystem::path& map_file, int min_weight) {
  Database db = open_map(map_file);
  MapContents contents;
  {
    auto st = db.prepare(
        "SELECT p.id, p.x, p.y, p.z, (SELECT COUNT(*) FROM observations o WHERE o.point_id = p.id) FROM map_points p "
        "ORDER BY p.id");
    while (st.step()) {
      contents.points.push_back({static_cast<uint64_t>(st.integer(0)), st.real(1), st.real(2), st.real(3),
                                 static_cast<int>(st.integer(4))});
    }
  }
  {
    auto st = db.prepare("SELECT id, timestamp, qx, qy, qz, qw, tx, ty, tz FROM keyframes ORDER BY id");
    while (st.step()) {
      const Eigen::Quaterniond q(st.real(5), st.real(2), st.real(3), st.real(4));
      const geometry::SE3 cam_from_world(q, geometry::Vec3(st.real(6), st.real(7), st.real(8)));
      contents.keyframes.push_back({static_cast<uint64_t>(st.integer(0)), st.real(1), cam_from_world.inverse()});
    }
  }
  {
    auto st = db.prepare("SELECT keyframe_id, other_id FROM covisibility WHERE keyframe_id < other_id AND weight >= ?");
    st.bind(1, static_cast<int64_t>(min_weight));
    while (st.step()) contents.covisibility.emplace_back(st.integer(0), st.integer(1));
  }
  {
    auto st = db.prepare("SELECT keyframe_id, other_id FROM loop_edges WHERE keyframe_id < other_id");
    while (st.step()) contents.loop_edges.emplace_back(st.integer(0), st.integer(1));
  }
  return contents;
}

}  // namespace crowdslam::mapdb
