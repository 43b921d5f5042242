#pragma once
// A thin RAII layer over SQLite's C API for the map database: a connection and prepared statements whose
// every failure becomes an InputError naming the database file and what was being done.
#include <sqlite3.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace crowdslam::mapdb {

class Statement;

class Database {
 public:
  enum class Mode { kReadOnly, kCreate };
  Database(const std::string& path, Mode mode);
  ~Database();
  Database(Database&& other) noexcept : path_(std::move(other.path_)), db_(other.db_) { other.db_ = nullptr; }
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;
  Database& operator=(Database&&) = delete;

  void exec(const std::string& sql);
  Statement prepare(const std::string& sql);
  [[nodiscard]] bool has_table(const std::string& name);
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] sqlite3* handle() const { return db_; }
  // Throws InputError "PATH: WHAT: sqlite message".
  [[noreturn]] void fail(const std::string& what) const;
  void close();  // closes now (a failure to close is an error); the destructor closes quietly

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

class Statement {
 public:
  Statement(Database& db, const std::string& sql);
  ~Statement();
  Statement(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  Statement& operator=(Statement&&) = delete;

  Statement& bind(int index, int64_t value);
  Statement& bind(int index, double value);
  Statement& bind(int index, const std::string& value);
  Statement& bind_blob(int index, const void* data, size_t bytes);
  Statement& bind_null(int index);
  // Steps once: true while a row is available.
  bool step();
  // Steps to the end (INSERT / UPDATE), then resets for the next bindings.
  void run();
  void reset();

  [[nodiscard]] int64_t integer(int column) const;
  [[nodiscard]] double real(int column) const;
  [[nodiscard]] std::string text(int column) const;
  [[nodiscard]] bool is_null(int column) const;
  [[nodiscard]] std::vector<uint8_t> blob(int column) const;
  [[nodiscard]] size_t blob_bytes(int column) const;
  [[nodiscard]] const void* blob_data(int column) const;

 private:
  Database* db_;
  sqlite3_stmt* stmt_ = nullptr;
  std::string sql_;
};

}  // namespace crowdslam::mapdb
