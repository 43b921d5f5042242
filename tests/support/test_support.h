#pragma once
// Shared helpers for the GoogleTest suite.
#include <filesystem>
#include <string>
#include <vector>

#include "crowdslam/util/error.h"

namespace crowdslam::test {

// ../shared (data and models), or $CROWDSLAM_SHARED when set.
std::filesystem::path shared_dir();
// Path of a shared dataset, e.g. shared_data("bonn_crowd"). Tests that need it call
// GTEST_SKIP() via require_shared() when it is absent, so the suite still runs elsewhere.
std::filesystem::path shared_data(const std::string& name);
bool shared_available(const std::string& name);

// Project source tree (config/ etc.).
std::filesystem::path source_dir();

// A fresh empty directory under the system temp dir, removed by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

void write_text(const std::filesystem::path& path, const std::string& content);
std::string read_text(const std::filesystem::path& path);

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
// Runs the built `crowdslam` binary with the given arguments (no shell quoting needed).
CliResult run_cli(const std::vector<std::string>& args);

// The message of the InputError that f() throws, or "" when it throws none.
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace crowdslam::test

#define CROWDSLAM_REQUIRE_SHARED(name)                                                    \
  do {                                                                                    \
    if (!crowdslam::test::shared_available(name)) GTEST_SKIP() << "shared data missing: " << name; \
  } while (0)
