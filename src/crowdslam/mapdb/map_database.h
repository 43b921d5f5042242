#pragma once
// Maps that outlive a run: the whole SLAM map in one SQLite file (schema in docs/MAP_FORMAT.md).
//
// save_map() writes keyframes (pose, keypoints, descriptors, right coordinates and depths), map points
// (position, descriptor, normal, depth range, observations, statistics), the covisibility weights, the
// spanning tree and the loop edges, plus what the map needs to be reused: the camera and settings that
// matter (MapIdentity) and where it came from (MapOrigin). One transaction into "<file>.tmp.<pid>",
// fsync, rename: a reader never sees a half-written map, and a failed save leaves the old file as it was.
//
// load_map() checks the file (SQLite integrity, schema version, tables) and the identity against the
// loading system's before it creates anything; every mismatch is an InputError naming the file and what
// differs. Bags of words are recomputed from the descriptors with the loading system's vocabulary (the
// keyframe database is the caller's: it adds the returned keyframes).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/geometry/camera.h"
#include "crowdslam/map/map.h"
#include "crowdslam/map/scale_levels.h"

namespace crowdslam::map {
class KeyFrame;
}

namespace crowdslam::mapdb {

constexpr int kSchemaVersion = 1;

// What must agree between the map and the system that loads it.
struct MapIdentity {
  std::string sensor;  // "mono", "stereo", "rgbd"
  geometry::PinholeCamera camera;  // the camera the keyframes' undistorted keypoints belong to
  double depth_map_factor = 0;     // RGB-D only (0 otherwise)
  int orb_features = 0;            // informational: a different budget still matches
  double orb_scale_factor = 0;
  int orb_levels = 0;
  std::string vocabulary_hash;     // content hash (vocabulary_hash()), "" = no vocabulary
  uint64_t vocabulary_words = 0;
};

// Where the map came from (kept when a loaded map is saved again).
struct MapOrigin {
  std::string dataset;
  std::string created_utc;        // ISO 8601
  std::string crowdslam_version;
  std::string end_state;          // of the run that saved it: completed, interrupted, failed: ...
};

struct MapHeader {
  int schema_version = kSchemaVersion;
  MapIdentity identity;
  MapOrigin origin;
};

// Counts and extent, for `crowdslam map info`.
struct MapInfo {
  MapHeader header;
  size_t keyframes = 0;
  size_t map_points = 0;
  size_t observations = 0;
  size_t covisibility_edges = 0;
  size_t loop_edges = 0;
  double points_min[3] = {0, 0, 0};
  double points_max[3] = {0, 0, 0};
  uint64_t file_bytes = 0;
};

// A content hash of a vocabulary (tree, words and weights; independent of the file format it came from).
std::string vocabulary_hash(const bow::Vocabulary& vocabulary);

// "" when a map with `stored` identity can be used by a system with `current`; otherwise what differs
// ("camera fx 535.4 in the map, 517.3 here; ...").
std::string identity_mismatch(const MapIdentity& stored, const MapIdentity& current);

// Writes every good keyframe and map point of `map` (no lock taken: call it when no thread writes the map).
void save_map(const std::filesystem::path& path, const map::Map& map, const MapHeader& header);

// Reads and checks the file's header only (also validates the schema and the tables).
MapHeader read_map_header(const std::filesystem::path& path);
MapInfo read_map_info(const std::filesystem::path& path);

struct LoadedMap {
  MapHeader header;
  std::vector<std::shared_ptr<map::KeyFrame>> keyframes;  // by id
  size_t map_points = 0;
};

// Loads the map into `map` (which must be empty), with the loading system's camera, scale levels and
// vocabulary (null: no bags of words). Throws InputError when the file is bad or its identity does not
// match `expected`.
LoadedMap load_map(const std::filesystem::path& path, const MapIdentity& expected, map::Map& map,
                   const std::shared_ptr<const geometry::PinholeCamera>& camera,
                   const std::shared_ptr<const map::ScaleLevels>& levels, const bow::Vocabulary* vocabulary);

}  // namespace crowdslam::mapdb
