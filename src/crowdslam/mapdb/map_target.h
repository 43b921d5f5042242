#pragma once
// Where a map (or an export of one) may be written. Saving renames a new file over the path, so the
// path is checked first: only a regular file that is a crowdslam map may be replaced, and only when the
// user said so (--overwrite). A device, FIFO, socket, directory or symbolic link, or a regular file that
// is not a crowdslam map (a settings file, a dataset's rgb.txt), is never replaced.
#include <filesystem>
#include <string>

namespace crowdslam::mapdb {

enum class PathKind {
  kMissing,     // nothing there
  kMap,         // a regular file that is a crowdslam map database (it may be corrupt)
  kOtherFile,   // a regular file of anything else
  kNotRegular,  // directory, device, FIFO, socket, symbolic link
};

// What `path` names (never follows a symbolic link, never opens a special file).
PathKind path_kind(const std::filesystem::path& path);

// Throws InputError "OPTION PATH: ..." unless a map may be written at `path`: it is a non-empty path
// whose directory exists, and nothing is there, or a crowdslam map with `overwrite`.
void check_map_target(const std::filesystem::path& path, bool overwrite, const std::string& option);

// Throws InputError "OPTION PATH: ..." unless an export (PLY, trajectory) may be written at `path`:
// not the map being read, and nothing there or a regular file that is not a crowdslam map.
void check_export_target(const std::filesystem::path& path, const std::filesystem::path& map_file,
                         const std::string& option);

}  // namespace crowdslam::mapdb
