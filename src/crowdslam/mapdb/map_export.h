#pragma once
// Exports of a saved map for other tools: the points as a binary PLY (x, y, z as float32, plus the number
// of keyframes observing each point as "observations", uint32; read by Open3D, CloudCompare, MeshLab),
// the keyframe positions as a PLY, and the keyframe trajectory in TUM format (world_from_cam).
#include <filesystem>

namespace crowdslam::mapdb {

// Each returns the number of elements written; files are written atomically. Throws InputError.
size_t export_points_ply(const std::filesystem::path& map_file, const std::filesystem::path& ply);
size_t export_keyframes_ply(const std::filesystem::path& map_file, const std::filesystem::path& ply);
size_t export_keyframe_trajectory(const std::filesystem::path& map_file, const std::filesystem::path& tum);

}  // namespace crowdslam::mapdb
