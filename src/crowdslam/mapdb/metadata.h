#pragma once
// MapHeader <-> the metadata table's key/value rows (doubles written with 17 significant digits, so
// they read back exactly).
#include <map>
#include <string>

#include "crowdslam/mapdb/map_database.h"

namespace crowdslam::mapdb {

std::map<std::string, std::string> header_to_metadata(const MapHeader& header);
// Throws InputError "PATH: corrupt map: metadata KEY missing / is not a finite number / is out of range".
MapHeader header_from_metadata(const std::map<std::string, std::string>& rows, const std::string& path);

}  // namespace crowdslam::mapdb
