// read_map_header(), read_map_info(), load_map(): checks first, then the map objects.
#include <cmath>
#include <cstring>
#include <map>
#include <system_error>
#include <unordered_map>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/mapdb/map_checks.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/metadata.h"
#include "crowdslam/mapdb/schema.h"
#include "crowdslam/mapdb/sqlite.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::mapdb {

namespace {

std::map<std::string, std::string> metadata_rows(Database& db);

// Opens an existing file and checks that it is a complete map database of a schema we read, whose rows
// hold what they should (map_checks.h).
Database open_checked(const std::filesystem::path& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (error || status.type() == std::filesystem::file_type::not_found) {
    throw InputError(path.string() + ": no such map file");
  }
  if (status.type() == std::filesystem::file_type::directory) throw InputError(path.string() + ": is a directory, not a map file");
  if (status.type() != std::filesystem::file_type::regular) throw InputError(path.string() + ": not a regular file");
  Database db(path.string(), Database::Mode::kReadOnly);
  {
    auto check = db.prepare("PRAGMA quick_check");
    std::string result = check.step() ? check.text(0) : std::string("no answer");
    if (result != "ok") {
      // SQLite's report spans lines ("*** in database main ***\nPage 3: ..."): one line, clipped.
      for (char& c : result) {
        if (c == '\n' || c == '\r') c = ' ';
      }
      throw InputError(path.string() + ": the map database is corrupt: " + clip_text(result, 200));
    }
  }
  if (!db.has_table("schema_version")) {
    throw InputError(path.string() + ": not a crowdslam map (no schema_version table)");
  }
  auto version = db.prepare("SELECT version FROM schema_version");
  if (!version.step()) throw InputError(path.string() + ": schema_version table is empty");
  const int64_t found = version.integer(0);
  if (found > kSchemaVersion) {
    throw InputError(path.string() + ": map schema version " + std::to_string(found) +
                     " is newer than this crowdslam reads (" + std::to_string(kSchemaVersion) + ")");
  }
  if (found < 1) throw InputError(path.string() + ": invalid map schema version " + std::to_string(found));
  for (size_t i = 0; i < kNumTables; ++i) {
    if (!db.has_table(kTables[i])) throw InputError(path.string() + ": table " + kTables[i] + " missing");
  }
  check_map_rows(db);
  checked_next_ids(db, metadata_rows(db));
  return db;
}

std::map<std::string, std::string> metadata_rows(Database& db) {
  std::map<std::string, std::string> rows;
  auto st = db.prepare("SELECT key, value FROM metadata");
  while (st.step()) rows[st.text(0)] = st.text(1);
  return rows;
}

MapHeader header_of(Database& db) {
  MapHeader header = header_from_metadata(metadata_rows(db), db.path());
  auto version = db.prepare("SELECT version FROM schema_version");
  version.step();
  header.schema_version = static_cast<int>(version.integer(0));
  return header;
}

float get_f32(const uint8_t* p) {
  float value;
  std::memcpy(&value, p, 4);
  return value;
}

int32_t get_i32(const uint8_t* p) {
  int32_t value;
  std::memcpy(&value, p, 4);
  return value;
}

[[noreturn]] void corrupt(const Database& db, const std::string& what) {
  throw InputError(db.path() + ": corrupt map: " + what);
}

std::shared_ptr<map::FrameFeatures> read_features(const Database& db, const Statement& row, uint64_t id,
                                                  const geometry::PinholeCamera& camera, int levels,
                                                  const bow::Vocabulary* vocabulary) {
  // Sizes by division, never by multiplying a stored count (which could wrap around).
  const int64_t count = row.integer(11);
  const size_t key_bytes = row.blob_bytes(12);
  if (count < 0 || key_bytes % kKeypointRecordBytes != 0 || key_bytes / kKeypointRecordBytes != static_cast<uint64_t>(count) ||
      row.blob_bytes(13) % kDescriptorBytes != 0 || row.blob_bytes(13) / kDescriptorBytes != static_cast<uint64_t>(count)) {
    corrupt(db, "keyframe " + std::to_string(id) + ": keypoint or descriptor blob of the wrong size");
  }
  const auto n = static_cast<size_t>(count);
  auto f = std::make_shared<map::FrameFeatures>();
  f->keys.resize(n);
  f->keys_un.resize(n);
  f->right_u.resize(n);
  f->depth_m.resize(n);
  const auto* p = static_cast<const uint8_t*>(row.blob_data(12));
  bool any_right = false;
  for (size_t i = 0; i < n; ++i, p += kKeypointRecordBytes) {
    for (size_t offset = 0; offset < 36; offset += 4) {
      if (!std::isfinite(get_f32(p + offset))) {
        corrupt(db, "keyframe " + std::to_string(id) + ": keypoint " + std::to_string(i) + " holds a non-finite number");
      }
    }
    if (get_i32(p + 36) < 0 || get_i32(p + 36) >= levels) {
      corrupt(db, "keyframe " + std::to_string(id) + ": keypoint " + std::to_string(i) + ": pyramid level " +
                      std::to_string(get_i32(p + 36)) + " outside 0-" + std::to_string(levels - 1));
    }
    cv::KeyPoint u(get_f32(p + 8), get_f32(p + 12), get_f32(p + 16), get_f32(p + 20), get_f32(p + 24),
                   get_i32(p + 36), get_i32(p + 40));
    cv::KeyPoint k = u;
    k.pt = {get_f32(p), get_f32(p + 4)};
    f->keys[i] = k;
    f->keys_un[i] = u;
    f->right_u[i] = get_f32(p + 28);
    f->depth_m[i] = get_f32(p + 32);
    any_right = any_right || f->right_u[i] >= 0;
  }
  if (!any_right && camera.bf == 0) {
    f->right_u.assign(n, -1.0f);
  }
  f->descriptors = cv::Mat(static_cast<int>(n), 32, CV_8UC1);
  if (n > 0) std::memcpy(f->descriptors.data, row.blob_data(13), n * kDescriptorBytes);
  f->grid = map::FeatureGrid(f->keys_un, camera.undistorted_bounds());
  if (vocabulary && !vocabulary->empty() && n > 0) vocabulary->transform(f->descriptors, f->bow, f->bow_features);
  return f;
}

}  // namespace

MapHeader read_map_header(const std::filesystem::path& path) {
  Database db = open_checked(path);
  return header_of(db);
}

MapInfo read_map_info(const std::filesystem::path& path) {
  Database db = open_checked(path);
  MapInfo info;
  info.header = header_of(db);
  const auto count = [&](const char* table) {
    auto st = db.prepare(std::string("SELECT COUNT(*) FROM ") + table);
    st.step();
    return static_cast<size_t>(st.integer(0));
  };
  info.keyframes = count("keyframes");
  info.map_points = count("map_points");
  info.observations = count("observations");
  info.covisibility_edges = count("covisibility");
  info.loop_edges = count("loop_edges");
  auto bounds = db.prepare("SELECT MIN(x), MIN(y), MIN(z), MAX(x), MAX(y), MAX(z) FROM map_points");
  if (bounds.step() && !bounds.is_null(0)) {
    for (int i = 0; i < 3; ++i) {
      info.points_min[i] = bounds.real(i);
      info.points_max[i] = bounds.real(3 + i);
    }
  }
  info.file_bytes = std::filesystem::file_size(path);
  return info;
}

LoadedMap load_map(const std::filesystem::path& path, const MapIdentity& expected, map::Map& map,
                   const std::shared_ptr<const geometry::PinholeCamera>& camera,
                   const std::shared_ptr<const map::ScaleLevels>& levels, const bow::Vocabulary* vocabulary) {
  Database db = open_checked(path);
  LoadedMap loaded;
  loaded.header = header_of(db);
  const std::string mismatch = identity_mismatch(loaded.header.identity, expected);
  if (!mismatch.empty()) throw InputError(path.string() + ": the map does not fit this run: " + mismatch);
  if (map.num_keyframes() > 0) throw InputError(path.string() + ": a map can only be loaded before the first frame");
  const auto rows = metadata_rows(db);

  std::unordered_map<uint64_t, std::shared_ptr<map::KeyFrame>> by_id;
  std::unordered_map<uint64_t, int64_t> parents;
  {
    auto st = db.prepare("SELECT * FROM keyframes ORDER BY id");
    while (st.step()) {
      const auto id = static_cast<uint64_t>(st.integer(0));
      const Eigen::Quaterniond q(st.real(6), st.real(3), st.real(4), st.real(5));
      if (std::abs(q.norm() - 1.0) > 1e-6) corrupt(db, "keyframe " + std::to_string(id) + ": pose is not a rotation");
      const auto pose = geometry::SE3::from_unit_quaternion(q, geometry::Vec3(st.real(7), st.real(8), st.real(9)));
      auto kf = std::make_shared<map::KeyFrame>(id, static_cast<uint64_t>(st.integer(1)), st.real(2), camera, levels,
                                                read_features(db, st, id, *camera, levels->num_levels, vocabulary), pose);
      if (!st.is_null(10)) parents[id] = st.integer(10);
      by_id[id] = kf;
      loaded.keyframes.push_back(std::move(kf));
    }
  }
  const auto keyframe = [&](int64_t id, const std::string& where) {
    const auto it = by_id.find(static_cast<uint64_t>(id));
    if (it == by_id.end()) corrupt(db, where + " refers to keyframe " + std::to_string(id) + ", which is not stored");
    return it->second;
  };

  std::vector<std::shared_ptr<map::MapPoint>> points;
  std::unordered_map<uint64_t, size_t> point_index;
  {
    auto st = db.prepare("SELECT * FROM map_points ORDER BY id");
    while (st.step()) {
      const auto id = static_cast<uint64_t>(st.integer(0));
      if (st.blob_bytes(9) != kDescriptorBytes) corrupt(db, "map point " + std::to_string(id) + ": descriptor size");
      auto reference = keyframe(st.integer(10), "map point " + std::to_string(id));
      auto point = std::make_shared<map::MapPoint>(id, geometry::Vec3(st.real(1), st.real(2), st.real(3)), reference,
                                                   static_cast<uint64_t>(st.integer(11)));
      map::MapPoint::SavedState state;
      state.normal = geometry::Vec3(st.real(4), st.real(5), st.real(6));
      state.min_distance = static_cast<float>(st.real(7));
      state.max_distance = static_cast<float>(st.real(8));
      state.visible = static_cast<int>(st.integer(12));
      state.found = static_cast<int>(st.integer(13));
      map::Descriptor descriptor;
      std::memcpy(descriptor.data(), st.blob_data(9), kDescriptorBytes);
      point->restore(state, descriptor);
      point_index[id] = points.size();
      points.push_back(std::move(point));
    }
  }
  {
    auto st = db.prepare("SELECT point_id, keyframe_id, keypoint_index FROM observations ORDER BY point_id, keyframe_id");
    while (st.step()) {
      const auto pid = static_cast<uint64_t>(st.integer(0));
      const auto it = point_index.find(pid);
      if (it == point_index.end()) corrupt(db, "an observation refers to map point " + std::to_string(pid) + ", which is not stored");
      auto kf = keyframe(st.integer(1), "an observation of map point " + std::to_string(pid));
      const int64_t index = st.integer(2);
      if (index < 0 || static_cast<size_t>(index) >= kf->features->size() || kf->map_point(static_cast<size_t>(index))) {
        corrupt(db, "observation of map point " + std::to_string(pid) + " by keyframe " + std::to_string(kf->id) +
                        ": keypoint index " + std::to_string(index) + " invalid or used twice");
      }
      const auto& point = points[it->second];
      point->add_observation(kf, static_cast<size_t>(index));
      kf->add_map_point(static_cast<size_t>(index), point);
    }
  }
  {
    auto st = db.prepare("SELECT keyframe_id, other_id, weight FROM covisibility ORDER BY keyframe_id, other_id");
    while (st.step()) {
      auto kf = keyframe(st.integer(0), "a covisibility edge");
      kf->add_connection(keyframe(st.integer(1), "a covisibility edge"), static_cast<int>(st.integer(2)));
    }
  }
  for (const auto& kf : loaded.keyframes) {
    const auto it = parents.find(kf->id);
    kf->restore_parent(it == parents.end() ? nullptr : keyframe(it->second, "keyframe " + std::to_string(kf->id)));
  }
  {
    auto st = db.prepare("SELECT keyframe_id, other_id FROM loop_edges ORDER BY keyframe_id, other_id");
    while (st.step()) keyframe(st.integer(0), "a loop edge")->add_loop_edge(keyframe(st.integer(1), "a loop edge"));
  }
  for (const auto& kf : loaded.keyframes) map.add_keyframe(kf);
  for (const auto& point : points) map.add_map_point(point);
  const NextIds next = checked_next_ids(db, rows);
  map.restore_id_counters(next.keyframe, next.map_point);
  loaded.map_points = points.size();
  return loaded;
}

}  // namespace crowdslam::mapdb
