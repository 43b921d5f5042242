#pragma once
// Writing output files without ever leaving a half-written one behind.
//
// AtomicFile writes into "<path>.tmp.<pid>" and renames it onto <path> on commit(), after an fsync of the
// data (and of the directory after the rename). If the object is destroyed without commit() (an exception
// was thrown while writing), the temporary is removed and <path> is untouched. While open, the temporary
// is registered with util/interrupt.h, so SIGINT/SIGTERM/SIGHUP remove it too.
#include <filesystem>
#include <fstream>
#include <string>

namespace crowdslam {

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ostream& stream() { return out_; }
  // Flushes, checks the stream, renames into place. Throws InputError if anything failed.
  void commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path tmp_path_;
  std::ofstream out_;
  bool committed_ = false;
  int registry_slot_ = -1;
};

// Convenience: atomically write a whole string.
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

// Removes a directory tree created by a failed run (best effort; never throws).
void remove_quietly(const std::filesystem::path& path);

// fsync() of a directory, so renames and new entries in it survive a crash (best effort).
void sync_directory(const std::filesystem::path& directory);

}  // namespace crowdslam
