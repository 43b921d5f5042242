#include "crowdslam/mapdb/map_target.h"

#include <cstring>
#include <fstream>

#include "crowdslam/mapdb/sqlite.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::mapdb {

namespace {
bool is_crowdslam_map(const std::filesystem::path& path) {
  char magic[16] = {};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in.read(magic, sizeof magic)) return false;
  }
  if (std::memcmp(magic, "SQLite format 3", 16) != 0) return false;
  try {
    Database db(path.string(), Database::Mode::kReadOnly);
    return db.has_table("schema_version") && db.has_table("metadata") && db.has_table("keyframes");
  } catch (const InputError&) {
    return false;
  }
}

std::string quoted_path(const std::string& option, const std::filesystem::path& path) {
  return option + " " + clip_text(path.string());
}
}  // namespace

PathKind path_kind(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::symlink_status(path, ec);
  if (ec || status.type() == std::filesystem::file_type::not_found) return PathKind::kMissing;
  if (status.type() != std::filesystem::file_type::regular) return PathKind::kNotRegular;
  return is_crowdslam_map(path) ? PathKind::kMap : PathKind::kOtherFile;
}

void check_map_target(const std::filesystem::path& path, bool overwrite, const std::string& option) {
  if (path.empty()) throw InputError(option + ": empty path (give the map file to write, e.g. map.db)");
  const auto dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw InputError(quoted_path(option, path) + ": directory " + clip_text(dir.string()) + " does not exist");
  }
  switch (path_kind(path)) {
    case PathKind::kMissing:
      return;
    case PathKind::kMap:
      if (overwrite) return;
      throw InputError(quoted_path(option, path) + ": a map already exists there (--overwrite replaces it)");
    case PathKind::kOtherFile:
      throw InputError(quoted_path(option, path) +
                       ": exists and is not a crowdslam map; refusing to replace it (choose another path)");
    case PathKind::kNotRegular:
      throw InputError(quoted_path(option, path) +
                       ": exists and is not a regular file (a directory, device, FIFO, socket or link); refusing "
                       "to replace it");
  }
}

void check_export_target(const std::filesystem::path& path, const std::filesystem::path& map_file,
                         const std::string& option) {
  if (path.empty()) throw InputError(option + ": empty path");
  std::error_code ec;
  if (std::filesystem::equivalent(path, map_file, ec) && !ec) {
    throw InputError(quoted_path(option, path) + ": is the map being exported; refusing to replace it");
  }
  switch (path_kind(path)) {
    case PathKind::kMissing:
    case PathKind::kOtherFile:
      return;
    case PathKind::kMap:
      throw InputError(quoted_path(option, path) + ": is a crowdslam map; refusing to replace it with an export");
    case PathKind::kNotRegular:
      throw InputError(quoted_path(option, path) +
                       ": exists and is not a regular file (a directory, device, FIFO, socket or link); refusing "
                       "to replace it");
  }
}

}  // namespace crowdslam::mapdb
