#include "crowdslam/util/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "crowdslam/util/error.h"
#include "crowdslam/util/interrupt.h"

namespace crowdslam {

namespace {
// fsync() of a file or directory by path; errno's message on failure, "" on success.
std::string sync_path(const std::filesystem::path& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) return std::strerror(errno);
  const int rc = ::fsync(fd);
  const int saved = errno;
  ::close(fd);
  return rc == 0 ? "" : std::strerror(saved);
}
}  // namespace

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)) {
  tmp_path_ = path_;
  tmp_path_ += ".tmp." + std::to_string(::getpid());
  std::error_code ec;
  if (path_.has_parent_path() && !std::filesystem::is_directory(path_.parent_path(), ec)) {
    throw input_error(path_.string(), "output directory does not exist");
  }
  registry_slot_ = temp_files::add(tmp_path_.string());
  out_.open(tmp_path_, std::ios::out | std::ios::trunc | std::ios::binary);
  if (!out_) {
    const int saved = errno;
    temp_files::remove(registry_slot_);
    throw input_error(path_.string(), std::string("cannot open for writing: ") + std::strerror(saved));
  }
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(tmp_path_, ec);
  }
  temp_files::remove(registry_slot_);
}

void AtomicFile::commit() {
  errno = 0;
  out_.flush();
  const bool good = static_cast<bool>(out_);
  const int saved = errno;
  out_.close();
  if (!good || !out_) {
    throw input_error(path_.string(), std::string("write failed") + (saved ? std::string(": ") + std::strerror(saved) : ""));
  }
  // Durable before it replaces anything: the data first, then the rename, then the directory entry.
  if (const auto error = sync_path(tmp_path_, false); !error.empty()) {
    throw input_error(path_.string(), "cannot sync to disk: " + error);
  }
  std::error_code ec;
  std::filesystem::rename(tmp_path_, path_, ec);
  if (ec) throw input_error(path_.string(), "cannot rename temporary file: " + ec.message());
  committed_ = true;
  sync_directory(path_.has_parent_path() ? path_.parent_path() : std::filesystem::path("."));
}

void write_file_atomic(const std::filesystem::path& path, const std::string& content) {
  AtomicFile file(path);
  file.stream() << content;
  file.commit();
}

void remove_quietly(const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
}

void sync_directory(const std::filesystem::path& directory) { (void)sync_path(directory, true); }

}  // namespace crowdslam
