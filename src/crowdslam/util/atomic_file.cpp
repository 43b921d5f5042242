#include "crowdslam/util/atomic_file.h"

#include <unistd.h>

#include "crowdslam/util/error.h"

namespace crowdslam {

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)) {
  tmp_path_ = path_;
  tmp_path_ += ".tmp." + std::to_string(::getpid());
  if (path_.has_parent_path() && !std::filesystem::is_directory(path_.parent_path())) {
    throw input_error(path_.string(), "output directory does not exist");
  }
  out_.open(tmp_path_, std::ios::out | std::ios::trunc);
  if (!out_) throw input_error(path_.string(), "cannot open for writing");
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(tmp_path_, ec);
  }
}

void AtomicFile::commit() {
  out_.flush();
  const bool good = static_cast<bool>(out_);
  out_.close();
  if (!good) throw input_error(path_.string(), "write failed");
  std::error_code ec;
  std::filesystem::rename(tmp_path_, path_, ec);
  if (ec) throw input_error(path_.string(), "cannot rename temporary file: " + ec.message());
  committed_ = true;
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

}  // namespace crowdslam
