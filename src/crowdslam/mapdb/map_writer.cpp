// save_map(): the map into "<file>.tmp.<pid>" in one transaction, fsync, rename.
#include <fcntl.h>
#include <unistd.h>

#include <cstring>
#include <system_error>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/map_target.h"
#include "crowdslam/mapdb/metadata.h"
#include "crowdslam/mapdb/schema.h"
#include "crowdslam/mapdb/sqlite.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/interrupt.h"

namespace crowdslam::mapdb {

namespace {

void put_f32(std::vector<uint8_t>& out, float value) {
  uint8_t bytes[4];
  std::memcpy(bytes, &value, 4);
  out.insert(out.end(), bytes, bytes + 4);
}

void put_i32(std::vector<uint8_t>& out, int32_t value) {
  uint8_t bytes[4];
  std::memcpy(bytes, &value, 4);
  out.insert(out.end(), bytes, bytes + 4);
}

std::vector<uint8_t> pack_keypoints(const map::FrameFeatures& f) {
  std::vector<uint8_t> out;
  out.reserve(f.size() * kKeypointRecordBytes);
  for (size_t i = 0; i < f.size(); ++i) {
    const cv::KeyPoint& k = f.keys[i];
    const cv::KeyPoint& u = f.keys_un[i];
    put_f32(out, k.pt.x);
    put_f32(out, k.pt.y);
    put_f32(out, u.pt.x);
    put_f32(out, u.pt.y);
    put_f32(out, u.size);
    put_f32(out, u.angle);
    put_f32(out, u.response);
    put_f32(out, f.right_u.empty() ? -1.0f : f.right_u[i]);
    put_f32(out, f.depth_m.empty() ? -1.0f : f.depth_m[i]);
    put_i32(out, u.octave);
    put_i32(out, u.class_id);
  }
  return out;
}

void write_keyframes(Database& db, const std::vector<std::shared_ptr<map::KeyFrame>>& keyframes) {
  auto insert = db.prepare(
      "INSERT INTO keyframes VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  auto covisibility = db.prepare("INSERT INTO covisibility VALUES (?, ?, ?)");
  auto loops = db.prepare("INSERT INTO loop_edges VALUES (?, ?)");
  for (const auto& kf : keyframes) {
    const geometry::SE3 pose = kf->cam_from_world();
    const auto& q = pose.rotation();
    const auto& t = pose.translation();
    const auto& f = *kf->features;
    const auto keypoints = pack_keypoints(f);
    insert.bind(1, static_cast<int64_t>(kf->id)).bind(2, static_cast<int64_t>(kf->frame_id)).bind(3, kf->timestamp_s);
    insert.bind(4, q.x()).bind(5, q.y()).bind(6, q.z()).bind(7, q.w()).bind(8, t.x()).bind(9, t.y()).bind(10, t.z());
    const auto parent = kf->parent();
    if (parent && !parent->is_bad()) {
      insert.bind(11, static_cast<int64_t>(parent->id));
    } else {
      insert.bind_null(11);
    }
    insert.bind(12, static_cast<int64_t>(f.size()));
    insert.bind_blob(13, keypoints.data(), keypoints.size());
    const cv::Mat descriptors = f.descriptors.isContinuous() ? f.descriptors : f.descriptors.clone();
    insert.bind_blob(14, descriptors.data, descriptors.total() * descriptors.elemSize());
    insert.run();
    for (const auto& other : kf->connected_keyframes()) {
      if (other->is_bad()) continue;
      covisibility.bind(1, static_cast<int64_t>(kf->id)).bind(2, static_cast<int64_t>(other->id));
      covisibility.bind(3, static_cast<int64_t>(kf->weight(other->id)));
      covisibility.run();
    }
    for (const auto& other : kf->loop_edges()) {
      if (other->is_bad()) continue;
      loops.bind(1, static_cast<int64_t>(kf->id)).bind(2, static_cast<int64_t>(other->id));
      loops.run();
    }
  }
}

void write_points(Database& db, const std::vector<std::shared_ptr<map::MapPoint>>& points) {
  auto insert = db.prepare("INSERT INTO map_points VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  auto observation = db.prepare("INSERT INTO observations VALUES (?, ?, ?)");
  for (const auto& point : points) {
    if (point->is_bad()) continue;
    const auto observations = point->observations();
    // Only observations by keyframes that are saved (good ones).
    std::vector<std::pair<uint64_t, size_t>> kept;
    for (const auto& [kf_id, obs] : observations) {
      const auto kf = obs.keyframe.lock();
      if (kf && !kf->is_bad()) kept.emplace_back(kf_id, obs.index);
    }
    if (kept.empty()) continue;
    auto reference = point->reference_keyframe();
    const uint64_t reference_id = reference && !reference->is_bad() ? reference->id : kept.front().first;
    const auto state = point->saved_state();
    const auto world = point->world();
    const auto descriptor = point->descriptor();
    insert.bind(1, static_cast<int64_t>(point->id)).bind(2, world.x()).bind(3, world.y()).bind(4, world.z());
    insert.bind(5, state.normal.x()).bind(6, state.normal.y()).bind(7, state.normal.z());
    insert.bind(8, static_cast<double>(state.min_distance)).bind(9, static_cast<double>(state.max_distance));
    insert.bind_blob(10, descriptor.data(), descriptor.size());
    insert.bind(11, static_cast<int64_t>(reference_id)).bind(12, static_cast<int64_t>(point->first_frame_id));
    insert.bind(13, static_cast<int64_t>(state.visible)).bind(14, static_cast<int64_t>(state.found));
    insert.run();
    for (const auto& [kf_id, index] : kept) {
      observation.bind(1, static_cast<int64_t>(point->id)).bind(2, static_cast<int64_t>(kf_id));
      observation.bind(3, static_cast<int64_t>(index));
      observation.run();
    }
  }
}

void fsync_file(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw InputError(path.string() + ": cannot reopen to sync: " + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (rc != 0) throw InputError(path.string() + ": fsync failed: " + std::strerror(error));
}

}  // namespace

void save_map(const std::filesystem::path& path, const map::Map& map, const MapHeader& header) {
  // The caller checked the path (check_map_target) before its work; a special file put there since is
  // still never replaced.
  if (path.empty()) throw InputError("cannot save the map: empty path");
  if (path_kind(path) == PathKind::kNotRegular) {
    throw InputError(path.string() + ": cannot save the map: not a regular file (refusing to replace it)");
  }
  remove_stale_temporaries(path);  // of a save killed with SIGKILL
  const std::filesystem::path tmp = path.string() + ".tmp." + std::to_string(::getpid());
  std::error_code ignored;
  std::filesystem::remove(tmp, ignored);
  const int slot = temp_files::add(tmp.string());
  try {
    {
      Database db(tmp.string(), Database::Mode::kCreate);
      db.exec("PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF;");
      db.exec("BEGIN");
      db.exec(kSchemaSql);
      db.exec("INSERT INTO schema_version VALUES (" + std::to_string(header.schema_version) + ")");
      {
        auto meta = db.prepare("INSERT INTO metadata VALUES (?, ?)");
        auto rows = header_to_metadata(header);
        const auto [next_keyframe, next_point] = map.id_counters();
        rows["map.next_keyframe_id"] = std::to_string(next_keyframe);
        rows["map.next_map_point_id"] = std::to_string(next_point);
        for (const auto& [key, value] : rows) {
          meta.bind(1, key).bind(2, value);
          meta.run();
        }
      }  // statements are finalised before the database closes
      std::vector<std::shared_ptr<map::KeyFrame>> keyframes;
      for (auto& kf : map.keyframes()) {
        if (!kf->is_bad()) keyframes.push_back(std::move(kf));
      }
      write_keyframes(db, keyframes);
      write_points(db, map.map_points());
      db.exec("COMMIT");
      db.close();
    }
    fsync_file(tmp);
    std::filesystem::rename(tmp, path);
    sync_directory(path.has_parent_path() ? path.parent_path() : std::filesystem::path("."));
  } catch (const std::filesystem::filesystem_error& e) {
    std::filesystem::remove(tmp, ignored);
    temp_files::remove(slot);
    throw InputError(path.string() + ": cannot save the map: " + e.code().message());
  } catch (const InputError& e) {
    std::filesystem::remove(tmp, ignored);
    temp_files::remove(slot);
    // Errors of the database name the temporary: the user knows the file they asked for.
    std::string message = e.what();
    if (message.rfind(tmp.string() + ": ", 0) == 0) message = message.substr(tmp.string().size() + 2);
    throw InputError(path.string() + ": cannot save the map: " + message);
  } catch (...) {
    std::filesystem::remove(tmp, ignored);
    temp_files::remove(slot);
    throw;
  }
  temp_files::remove(slot);
}

}  // namespace crowdslam::mapdb
