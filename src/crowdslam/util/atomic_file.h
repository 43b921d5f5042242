#pragma once
// Writing output files without ever leaving a half-written one behind.
//
// AtomicFile refuses a <path> that is a directory, device, FIFO or socket (never replaced). It writes
// into "<path>.tmp.<pid>" and renames it onto <path> on commit(), after an fsync of the
// data (and of the directory after the rename). If the object is destroyed without commit() (an exception
// was thrown while writing), the temporary is removed and <path> is untouched. While open, the temporary
// is registered with util/interrupt.h, so SIGINT/SIGTERM/SIGHUP remove it too.
#include <filesystem>
#include <ostream>
#include <streambuf>
#include <string>
#include <vector>

namespace crowdslam {

namespace detail {
// An output buffer over a file descriptor that keeps the first write error's errno, so that a failed
// write says why (ENOSPC: "No space left on device", EFBIG, EIO), which std::ofstream does not.
class FdStreamBuf : public std::streambuf {
 public:
  FdStreamBuf() : buffer_(1 << 16) { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
  void attach(int fd) { fd_ = fd; }
  [[nodiscard]] int error() const { return error_; }
  bool flush_buffer();  // false on a write error (error() says which)

 protected:
  int_type overflow(int_type c) override;
  int sync() override { return flush_buffer() ? 0 : -1; }
  std::streamsize xsputn(const char* data, std::streamsize n) override;

 private:
  bool write_all(const char* data, size_t n);
  std::vector<char> buffer_;
  int fd_ = -1;
  int error_ = 0;
};
}  // namespace detail

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
  detail::FdStreamBuf buffer_;
  std::ostream out_{&buffer_};
  int fd_ = -1;
  bool committed_ = false;
  int registry_slot_ = -1;
};

// Convenience: atomically write a whole string.
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

// Removes a directory tree created by a failed run (best effort; never throws).
void remove_quietly(const std::filesystem::path& path);

// Removes "<path>.tmp.<pid>" files next to `path` (our temporaries' naming) whose process no longer
// runs: left by a writer killed with SIGKILL. Returns how many were removed; never throws.
size_t remove_stale_temporaries(const std::filesystem::path& path);

// The same for directories "<path>.tmp-<pid>" (a dataset or sprite set being written by `synth`).
size_t remove_stale_temporary_dirs(const std::filesystem::path& path);

// fsync() of a directory, so renames and new entries in it survive a crash (best effort).
void sync_directory(const std::filesystem::path& directory);

}  // namespace crowdslam
