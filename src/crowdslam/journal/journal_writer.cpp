#include "crowdslam/journal/journal_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "crowdslam/io/jpeg_encode.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"
#include "crowdslam/util/thread_priority.h"

namespace crowdslam::journal {

namespace {
std::string errno_text(int error) { return error ? std::strerror(error) : "unknown error"; }
}  // namespace

JournalWriter::JournalWriter(JournalWriterOptions options) : options_(std::move(options)) {
  if (options_.flush_every_poses == 0) options_.flush_every_poses = 1;
  if (options_.frame_queue_capacity == 0) options_.frame_queue_capacity = 1;
  const std::string path = options_.trajectory_path.string();
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw input_error(clip_text(path), "cannot open for writing: " + errno_text(errno));
  pending_ = io::trajectory_header(options_.format);
  if (!flush_pending()) {
    ::close(fd_);
    fd_ = -1;
    throw input_error(clip_text(path), "write failed: " + errno_text(errno));
  }
  if (!options_.frames_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options_.frames_dir, ec);
    if (ec) {
      ::close(fd_);
      fd_ = -1;
      throw input_error(clip_text(options_.frames_dir.string()), "cannot create directory: " + ec.message());
    }
  }
  thread_ = std::thread([this] {
    util::set_thread_name("cs-journal");
    run();
  });
}

JournalWriter::~JournalWriter() {
  try {
    close();
  } catch (...) {  // close() does not throw; a write error stays in error_
  }
}

void JournalWriter::append_pose(const io::StampedPose& pose) {
  {
    std::lock_guard lock(mutex_);
    if (closing_ || error_) return;
    Task task;
    task.pose = pose;
    tasks_.push_back(std::move(task));
  }
  work_cv_.notify_one();
}

void JournalWriter::save_frame(size_t index, std::function<cv::Mat()> draw) {
  {
    std::unique_lock lock(mutex_);
    if (queued_frames_ >= options_.frame_queue_capacity) {
      ++stats_.frame_waits;
      space_cv_.wait(lock, [this] { return queued_frames_ < options_.frame_queue_capacity || closing_ || error_; });
    }
    if (closing_ || error_) return;
    Task task;
    task.is_frame = true;
    task.index = index;
    task.draw = std::move(draw);
    tasks_.push_back(std::move(task));
    ++queued_frames_;
  }
  work_cv_.notify_one();
}

void JournalWriter::close() {
  {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    closing_ = true;
  }
  work_cv_.notify_all();
  space_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  bool failed = false;
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
    failed = static_cast<bool>(error_);
  }
  if (fd_ >= 0) {
    if (!failed) {
      const size_t poses = unflushed_;
      unflushed_ = 0;
      if (flush_pending()) {
        std::lock_guard lock(mutex_);
        stats_.poses_written += poses;
      } else {
        fail(options_.trajectory_path.string(), "write failed: " + errno_text(errno));
      }
    }
    ::close(fd_);
    fd_ = -1;
  }
}

bool JournalWriter::flush_pending() {
  size_t done = 0;
  while (done < pending_.size()) {
    const ssize_t n = ::write(fd_, pending_.data() + done, pending_.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int saved = errno != 0 ? errno : ENOSPC;
      // Cut a partly written batch back to its last complete line.
      const size_t last_newline = done > 0 ? pending_.rfind('\n', done - 1) : std::string::npos;
      const long long keep = written_bytes_ + (last_newline == std::string::npos ? 0 : static_cast<long long>(last_newline + 1));
      if (::ftruncate(fd_, keep) == 0) written_bytes_ = keep;
      ::lseek(fd_, written_bytes_, SEEK_SET);
      pending_.clear();
      errno = saved;
      return false;
    }
    done += static_cast<size_t>(n);
  }
  written_bytes_ += static_cast<long long>(pending_.size());
  pending_.clear();
  return true;
}

void JournalWriter::check() const {
  std::lock_guard lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

JournalWriterStats JournalWriter::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void JournalWriter::run() {
  while (true) {
    Task task;
    {
      std::unique_lock lock(mutex_);
      work_cv_.wait(lock, [this] { return !tasks_.empty() || closing_; });
      if (tasks_.empty() || error_) {
        tasks_.clear();
        return;  // closing with nothing left, or stopped by an error
      }
      task = std::move(tasks_.front());
      tasks_.pop_front();
    }
    if (task.is_frame) {
      write_frame(task.index, task.draw);
      std::lock_guard lock(mutex_);
      --queued_frames_;
      space_cv_.notify_all();
    } else {
      write_pose(task.pose);
    }
  }
}

void JournalWriter::write_pose(const io::StampedPose& pose) {
  pending_ += io::format_trajectory_line(pose, options_.format);
  if (++unflushed_ < options_.flush_every_poses) return;
  const size_t poses = unflushed_;
  unflushed_ = 0;
  if (!flush_pending()) {
    fail(options_.trajectory_path.string(), "write failed: " + errno_text(errno));
    return;
  }
  std::lock_guard lock(mutex_);
  stats_.poses_written += poses;
}

void JournalWriter::write_frame(size_t index, const std::function<cv::Mat()>& draw) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu.jpg", index);
  const auto path = options_.frames_dir / name;
  try {
    const cv::Mat image = draw();
    const std::vector<unsigned char> jpeg = io::encode_jpeg(image, options_.jpeg_quality);
    AtomicFile file(path);
    file.stream().write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
    file.commit();
    std::lock_guard lock(mutex_);
    ++stats_.frames_saved;
  } catch (const std::exception& e) {
    fail(path.string(), e.what());
  }
}

void JournalWriter::fail(const std::string& file, const std::string& message) {
  std::lock_guard lock(mutex_);
  if (error_) return;
  // An InputError from AtomicFile already names its file.
  const bool named = message.find(file) != std::string::npos;
  error_ = std::make_exception_ptr(named ? InputError(message) : input_error(clip_text(file), message));
  space_cv_.notify_all();
}

}  // namespace crowdslam::journal
