#include "crowdslam/mapdb/schema.h"

namespace crowdslam::mapdb {

const char* const kSchemaSql = R"SQL(
CREATE TABLE schema_version (version INTEGER NOT NULL);
CREATE TABLE metadata (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE keyframes (
  id INTEGER PRIMARY KEY, frame_id INTEGER NOT NULL, timestamp REAL NOT NULL,
  qx REAL NOT NULL, qy REAL NOT NULL, qz REAL NOT NULL, qw REAL NOT NULL,
  tx REAL NOT NULL, ty REAL NOT NULL, tz REAL NOT NULL,
  parent_id INTEGER, num_keypoints INTEGER NOT NULL, keypoints BLOB NOT NULL, descriptors BLOB NOT NULL);
CREATE TABLE map_points (
  id INTEGER PRIMARY KEY, x REAL NOT NULL, y REAL NOT NULL, z REAL NOT NULL,
  nx REAL NOT NULL, ny REAL NOT NULL, nz REAL NOT NULL, min_distance REAL NOT NULL, max_distance REAL NOT NULL,
  descriptor BLOB NOT NULL, reference_keyframe_id INTEGER NOT NULL, first_frame_id INTEGER NOT NULL,
  visible INTEGER NOT NULL, found INTEGER NOT NULL);
CREATE TABLE observations (
  point_id INTEGER NOT NULL, keyframe_id INTEGER NOT NULL, keypoint_index INTEGER NOT NULL,
  PRIMARY KEY (point_id, keyframe_id));
CREATE TABLE covisibility (
  keyframe_id INTEGER NOT NULL, other_id INTEGER NOT NULL, weight INTEGER NOT NULL,
  PRIMARY KEY (keyframe_id, other_id));
CREATE TABLE loop_edges (keyframe_id INTEGER NOT NULL, other_id INTEGER NOT NULL, PRIMARY KEY (keyframe_id, other_id));
)SQL";

const char* const kTables[] = {"schema_version", "metadata",     "keyframes", "map_points",
                               "observations",   "covisibility", "loop_edges"};
const size_t kNumTables = sizeof(kTables) / sizeof(kTables[0]);

}  // namespace crowdslam::mapdb
