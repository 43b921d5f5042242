#include "crowdslam/util/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
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

namespace detail {
bool FdStreamBuf::write_all(const char* data, size_t n) {
  while (n > 0 && error_ == 0) {
    const ssize_t written = ::write(fd_, data, n);
    if (written < 0) {
      if (errno == EINTR) continue;
      error_ = errno;
      return false;
    }
    data += written;
    n -= static_cast<size_t>(written);
  }
  return error_ == 0;
}

bool FdStreamBuf::flush_buffer() {
  const auto n = static_cast<size_t>(pptr() - pbase());
  const bool ok = error_ == 0 && write_all(pbase(), n);
  setp(buffer_.data(), buffer_.data() + buffer_.size());
  return ok;
}

FdStreamBuf::int_type FdStreamBuf::overflow(int_type c) {
  if (!flush_buffer()) return traits_type::eof();
  if (!traits_type::eq_int_type(c, traits_type::eof())) {
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
  }
  return traits_type::not_eof(c);
}

std::streamsize FdStreamBuf::xsputn(const char* data, std::streamsize n) {
  if (n <= epptr() - pptr()) {
    std::memcpy(pptr(), data, static_cast<size_t>(n));
    pbump(static_cast<int>(n));
    return n;
  }
  if (!flush_buffer() || !write_all(data, static_cast<size_t>(n))) return 0;
  return n;
}
}  // namespace detail

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)) {
  tmp_path_ = path_;
  tmp_path_ += ".tmp." + std::to_string(::getpid());
  std::error_code ec;
  if (path_.has_parent_path() && !std::filesystem::is_directory(path_.parent_path(), ec)) {
    throw input_error(path_.string(), "output directory does not exist");
  }
  // Renaming over a device, FIFO, socket or directory would replace it (as root, /dev/null itself).
  const auto type = std::filesystem::symlink_status(path_, ec).type();
  if (!ec && type != std::filesystem::file_type::not_found && type != std::filesystem::file_type::regular &&
      type != std::filesystem::file_type::symlink) {
    throw input_error(path_.string(), "exists and is not a regular file (a directory, device, FIFO or socket); "
                                      "refusing to replace it");
  }
  registry_slot_ = temp_files::add(tmp_path_.string());
  fd_ = ::open(tmp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    const int saved = errno;
    temp_files::remove(registry_slot_);
    throw input_error(path_.string(), std::string("cannot open for writing: ") + std::strerror(saved));
  }
  buffer_.attach(fd_);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(tmp_path_, ec);
  }
  temp_files::remove(registry_slot_);
}

void AtomicFile::commit() {
  out_.flush();
  const bool good = static_cast<bool>(out_) && buffer_.error() == 0;
  if (!good) {
    const int saved = buffer_.error();
    throw input_error(path_.string(), std::string("write failed: ") +
                                          (saved ? std::strerror(saved) : "the output stream failed"));
  }
  // Durable before it replaces anything: the data first, then the rename, then the directory entry.
  const int sync_rc = ::fsync(fd_);
  const int sync_error = errno;
  const int close_rc = ::close(fd_);
  const int close_error = errno;
  fd_ = -1;
  if (sync_rc != 0) throw input_error(path_.string(), std::string("cannot sync to disk: ") + std::strerror(sync_error));
  if (close_rc != 0) throw input_error(path_.string(), std::string("write failed: ") + std::strerror(close_error));
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

namespace {

// Removes entries "<name><separator><pid>" next to `path` whose process no longer runs. A regular file
// (dirs = false) or a directory (dirs = true) of exactly that naming; never a symlink or a device.
size_t remove_stale(const std::filesystem::path& path, const std::string& separator, bool dirs) {
  const std::string prefix = path.filename().string() + separator;
  const auto dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  size_t removed = 0;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;  // that process still runs (or is not ours to judge)
    std::error_code ignored;
    const auto type = it->symlink_status(ignored).type();
    const auto wanted = dirs ? std::filesystem::file_type::directory : std::filesystem::file_type::regular;
    if (type != wanted) continue;
    if (dirs ? std::filesystem::remove_all(it->path(), ignored) > 0 : std::filesystem::remove(it->path(), ignored)) {
      ++removed;
    }
  }
  return removed;
}

}  // namespace

size_t remove_stale_temporaries(const std::filesystem::path& path) { return remove_stale(path, ".tmp.", false); }

size_t remove_stale_temporary_dirs(const std::filesystem::path& path) { return remove_stale(path, ".tmp-", true); }

void sync_directory(const std::filesystem::path& directory) { (void)sync_path(directory, true); }

}  // namespace crowdslam
