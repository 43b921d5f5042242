#include "crowdslam/mapdb/map_checks.h"

#include <vector>

#include "crowdslam/mapdb/schema.h"
#include "crowdslam/mapdb/sqlite.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::mapdb {

namespace {

enum class Kind { kFinite, kId, kOptionalId, kCount };

struct Column {
  const char* name;
  Kind kind;
};

struct TableCheck {
  const char* table;
  const char* row_label;  // SQL expression naming the row in a message
  std::vector<Column> columns;
  std::vector<std::string> extra;  // further "condition|message" checks
};

// SQL that is true when the column's value is bad.
std::string bad_value(const Column& c) {
  const std::string n = c.name;
  switch (c.kind) {
    case Kind::kFinite:
      return "typeof(" + n + ") NOT IN ('real','integer') OR NOT (abs(" + n + ") <= 1.7976931348623157e308)";
    case Kind::kId:
    case Kind::kCount:
      return "typeof(" + n + ") != 'integer' OR " + n + " < 0";
    case Kind::kOptionalId:
      return n + " IS NOT NULL AND (typeof(" + n + ") != 'integer' OR " + n + " < 0)";
  }
  return "0";
}

std::string what_is_wrong(const Column& c) {
  switch (c.kind) {
    case Kind::kFinite:
      return std::string(c.name) + " is not a finite number";
    case Kind::kId:
    case Kind::kOptionalId:
      return std::string(c.name) + " is not an id (an integer >= 0)";
    case Kind::kCount:
      return std::string(c.name) + " is not a count (an integer >= 0)";
  }
  return c.name;
}

const std::vector<TableCheck>& checks() {
  static const std::string keypoint_bytes = std::to_string(kKeypointRecordBytes);
  static const std::string descriptor_bytes = std::to_string(kDescriptorBytes);
  static const std::vector<TableCheck> all = {
      {"keyframes",
       "'keyframe ' || id",
       {{"id", Kind::kId}, {"frame_id", Kind::kId}, {"timestamp", Kind::kFinite}, {"qx", Kind::kFinite},
        {"qy", Kind::kFinite}, {"qz", Kind::kFinite}, {"qw", Kind::kFinite}, {"tx", Kind::kFinite},
        {"ty", Kind::kFinite}, {"tz", Kind::kFinite}, {"parent_id", Kind::kOptionalId},
        {"num_keypoints", Kind::kCount}},
       {"length(keypoints) != num_keypoints * " + keypoint_bytes +
            "|keypoints blob size does not match num_keypoints",
        "length(descriptors) != num_keypoints * " + descriptor_bytes +
            "|descriptors blob size does not match num_keypoints"}},
      {"map_points",
       "'map point ' || id",
       {{"id", Kind::kId}, {"x", Kind::kFinite}, {"y", Kind::kFinite}, {"z", Kind::kFinite},
        {"nx", Kind::kFinite}, {"ny", Kind::kFinite}, {"nz", Kind::kFinite}, {"min_distance", Kind::kFinite},
        {"max_distance", Kind::kFinite}, {"reference_keyframe_id", Kind::kId}, {"first_frame_id", Kind::kId},
        {"visible", Kind::kCount}, {"found", Kind::kCount}},
       {"length(descriptor) != " + descriptor_bytes + "|descriptor is not " + descriptor_bytes + " bytes"}},
      {"observations",
       "'observation of map point ' || point_id || ' by keyframe ' || keyframe_id",
       {{"point_id", Kind::kId}, {"keyframe_id", Kind::kId}, {"keypoint_index", Kind::kCount}},
       {}},
      {"covisibility",
       "'covisibility edge ' || keyframe_id || '-' || other_id",
       {{"keyframe_id", Kind::kId}, {"other_id", Kind::kId}, {"weight", Kind::kCount}},
       {}},
      {"loop_edges",
       "'loop edge ' || keyframe_id || '-' || other_id",
       {{"keyframe_id", Kind::kId}, {"other_id", Kind::kId}},
       {}},
  };
  return all;
}

[[noreturn]] void corrupt_row(const Database& db, const std::string& what) {
  throw InputError(db.path() + ": corrupt map: " + what);
}

// Strict: digits only (no sign, no spaces, no exponent), at most 18 of them.
bool parse_id(const std::string& text, uint64_t& value) {
  if (text.empty() || text.size() > 18 || text.find_first_not_of("0123456789") != std::string::npos) return false;
  value = std::stoull(text);
  return true;
}

}  // namespace

void check_map_rows(Database& db) {
  for (const TableCheck& t : checks()) {
    // One pass per table: the first bad column of the first bad row, as a message.
    std::string cases;
    for (const Column& c : t.columns) cases += " WHEN " + bad_value(c) + " THEN '" + what_is_wrong(c) + "'";
    for (const std::string& e : t.extra) {
      const auto bar = e.find('|');
      cases += " WHEN " + e.substr(0, bar) + " THEN '" + e.substr(bar + 1) + "'";
    }
    auto st = db.prepare("SELECT label, bad FROM (SELECT " + std::string(t.row_label) + " AS label, CASE" + cases +
                         " END AS bad FROM " + t.table + ") WHERE bad IS NOT NULL LIMIT 1");
    if (st.step()) {
      std::string label = clip_text(st.text(0), 100);
      for (char& c : label) {  // a blob where an id belongs: its bytes are not text
        if (static_cast<unsigned char>(c) >= 0x80) c = '?';
      }
      corrupt_row(db, label + ": " + st.text(1));
    }
  }
}

NextIds checked_next_ids(Database& db, const std::map<std::string, std::string>& metadata) {
  NextIds next;
  const auto read = [&](const char* key, const char* table, uint64_t& value) {
    const auto it = metadata.find(key);
    if (it == metadata.end()) corrupt_row(db, std::string("metadata ") + key + " missing");
    if (!parse_id(it->second, value)) {
      corrupt_row(db, std::string("metadata ") + key + " is not an id: " + clip_text(it->second, 60));
    }
    auto st = db.prepare(std::string("SELECT MAX(id) FROM ") + table);
    if (st.step() && !st.is_null(0) && static_cast<uint64_t>(st.integer(0)) >= value) {
      corrupt_row(db, std::string("metadata ") + key + " = " + it->second + " is not above the stored id " +
                      std::to_string(st.integer(0)) + " (new ones would overwrite stored ones)");
    }
  };
  read("map.next_keyframe_id", "keyframes", next.keyframe);
  read("map.next_map_point_id", "map_points", next.map_point);
  return next;
}

}  // namespace crowdslam::mapdb
