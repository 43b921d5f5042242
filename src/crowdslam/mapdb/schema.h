#pragma once
// The map database's tables (schema version 1; described for users in docs/MAP_FORMAT.md).
#include <cstddef>
#include <cstdint>

namespace crowdslam::mapdb {

// CREATE TABLE statements, one string.
extern const char* const kSchemaSql;
// Every table a valid file has.
extern const char* const kTables[];
extern const size_t kNumTables;

// Packed keypoint record in keyframes.keypoints (little-endian): float32 x, y (as detected), ux, uy
// (undistorted), size, angle, response, right_u (< 0: none), depth_m (<= 0: none); int32 octave, class_id.
constexpr size_t kKeypointRecordBytes = 44;
constexpr size_t kDescriptorBytes = 32;

}  // namespace crowdslam::mapdb
