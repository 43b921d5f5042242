#pragma once
// Row checks of a map database, run on every open (map info, export, load, optimise, view): every
// number a row stores is of its type and finite, ids are not negative, keypoint and descriptor blobs have
// the size their counts say, and the stored next ids are above every stored id (a new keyframe or point
// never takes the id of a loaded one). The first bad row is an InputError "PATH: corrupt map: WHAT".
#include <cstdint>
#include <map>
#include <string>

namespace crowdslam::mapdb {

class Database;

void check_map_rows(Database& db);

// The next ids stored in the metadata, checked against the stored ids (InputError "corrupt map").
struct NextIds {
  uint64_t keyframe = 0;
  uint64_t map_point = 0;
};
NextIds checked_next_ids(Database& db, const std::map<std::string, std::string>& metadata);

}  // namespace crowdslam::mapdb
