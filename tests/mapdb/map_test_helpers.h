#pragma once
// Shared by the map database tests: a synthetic sequence, runs that save / load maps, table dumps.
#include <sqlite3.h>

#include <filesystem>
#include <string>
#include <vector>

#include "crowdslam/run/run_sequence.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "run_test_options.h"
#include "test_support.h"

namespace crowdslam::test {

inline std::filesystem::path make_room(const TempDir& tmp, int people, int frames = 120) {
  synth::SynthOptions options;
  options.frames = frames;
  options.trajectory = synth::TrajectoryKind::kLine;
  options.people = people;
  options.seed = 3;
  const auto dir = tmp / ("room" + std::to_string(people));
  synth::write_sequence(options, dir);
  return dir;
}

inline run::RunOptions run_options(const std::filesystem::path& dataset, const std::filesystem::path& out) {
  return test::sequential_run_options(dataset, out);
}

// Every row of a table, rendered as text (blobs as hex), in primary-key order.
inline std::vector<std::string> dump_table(const std::filesystem::path& db_path, const std::string& table) {
  sqlite3* db = nullptr;
  std::vector<std::string> rows;
  if (sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(db);
    return {"cannot open " + db_path.string()};
  }
  sqlite3_stmt* st = nullptr;
  const std::string sql = "SELECT * FROM " + table + " ORDER BY 1, 2";
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &st, nullptr) != SQLITE_OK) {
    sqlite3_close(db);
    return {"cannot read " + table};
  }
  static const char* hex = "0123456789abcdef";
  while (sqlite3_step(st) == SQLITE_ROW) {
    std::string row;
    for (int c = 0; c < sqlite3_column_count(st); ++c) {
      if (sqlite3_column_type(st, c) == SQLITE_BLOB) {
        const auto* p = static_cast<const unsigned char*>(sqlite3_column_blob(st, c));
        for (int i = 0; i < sqlite3_column_bytes(st, c); ++i) {
          row += hex[p[i] >> 4];
          row += hex[p[i] & 15];
        }
      } else if (sqlite3_column_type(st, c) == SQLITE_FLOAT) {
        char buffer[40];
        std::snprintf(buffer, sizeof buffer, "%.17g", sqlite3_column_double(st, c));
        row += buffer;
      } else {
        const auto* t = sqlite3_column_text(st, c);
        row += t ? reinterpret_cast<const char*>(t) : "NULL";
      }
      row += '|';
    }
    rows.push_back(std::move(row));
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return rows;
}

inline void exec_sql(const std::filesystem::path& db_path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(db_path.c_str(), &db), SQLITE_OK);
  char* error = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error);
  const std::string message = error ? error : "";
  sqlite3_free(error);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << message;
}

}  // namespace crowdslam::test
