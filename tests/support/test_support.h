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
// A file's bytes (empty when it cannot be read) and writing bytes to one.
std::vector<unsigned char> read_bytes(const std::filesystem::path& path);
void write_bytes(const std::filesystem::path& path, const std::vector<unsigned char>& bytes);

// Two real bonn_crowd frames (colour and depth) copied into `dir` in TUM layout (rgb.txt, depth.txt).
struct TwoBonnFrames {
  std::filesystem::path colour[2];
  std::filesystem::path depth[2];
};
TwoBonnFrames copy_two_bonn_frames(const std::filesystem::path& dir);

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
// Runs the built `crowdslam` binary with the given arguments (no shell quoting needed).
CliResult run_cli(const std::vector<std::string>& args);

// Limits for a child process (setrlimit in the child before exec).
struct ChildLimits {
  long long max_file_bytes = -1;  // RLIMIT_FSIZE (writes beyond fail with EFBIG; SIGXFSZ ignored); -1 = none
};

// The `crowdslam` binary as a child process that a test can signal while it runs. stdout and stderr go
// to files in a temporary directory; the destructor kills (SIGKILL) and reaps a child still running.
class CliProcess {
 public:
  explicit CliProcess(const std::vector<std::string>& args, const ChildLimits& limits = {});
  ~CliProcess();
  CliProcess(const CliProcess&) = delete;
  CliProcess& operator=(const CliProcess&) = delete;

  void send_signal(int signal) const;
  // Waits until `predicate()` is true or the child exits or `timeout_s` passes; returns predicate().
  template <typename P>
  bool wait_until(P&& predicate, double timeout_s) {
    for (int i = 0; i < static_cast<int>(timeout_s * 200); ++i) {
      if (predicate()) return true;
      if (exited()) return predicate();
      sleep_ms(5);
    }
    return predicate();
  }
  // Waits for the child to exit (up to timeout_s; then kills it and fails the result with exit -1).
  CliResult wait(double timeout_s = 600);
  [[nodiscard]] bool exited();
  [[nodiscard]] std::string current_stderr() const;
  [[nodiscard]] int pid() const { return pid_; }

 private:
  static void sleep_ms(int ms);
  TempDir tmp_;
  int pid_ = -1;
  bool reaped_ = false;
  int status_ = 0;
};

// The port of the live viewer a `crowdslam run --viewer` or `crowdslam view` child prints
// ("viewer: http://127.0.0.1:PORT/"), waiting up to `timeout_s`; 0 when it did not print one.
int wait_for_viewer_port(CliProcess& process, double timeout_s = 60);

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
