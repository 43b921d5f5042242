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

#include <cstdint>
#include <utility>
#include <vector>

#include "crowdslam/geometry/se3.h"

namespace crowdslam::mapdb {

// The map's geometry only (for viewers): point positions with observation counts, keyframe poses,
// covisibility edges with at least `min_weight` shared points, loop edges (each edge once).
struct MapContents {
  struct Point {
    uint64_t id = 0;
    double x = 0, y = 0, z = 0;
    int observations = 0;
  };
  struct Keyframe {
    uint64_t id = 0;
    double timestamp_s = 0;
    geometry::SE3 world_from_cam;
  };
  std::vector<Point> points;
  std::vector<Keyframe> keyframes;
  std::vector<std::pair<uint64_t, uint64_t>> covisibility;
  std::vector<std::pair<uint64_t, uint64_t>> loop_edges;
};
MapContents read_map_contents(const std::filesystem::path& map_file, int min_weight = 100);

// How much of a map was built on moving things: the map points observed on a masked pixel in any
// keyframe whose frame has a mask in `mask_dir` (NNNNNN.png by frame index, non-zero = moving; the
// mask/ folder of `crowdslam synth --movers`). Throws InputError when no keyframe has a mask.
struct MaskCount {
  int keyframes_with_mask = 0;
  size_t points_checked = 0;  // points seen by those keyframes
  size_t points_on_mask = 0;
  [[nodiscard]] double fraction() const {
    return points_checked == 0 ? 0.0 : static_cast<double>(points_on_mask) / static_cast<double>(points_checked);
  }
};
MaskCount count_points_on_masks(const std::filesystem::path& map_file, const std::filesystem::path& mask_dir);

}  // namespace crowdslam::mapdb
