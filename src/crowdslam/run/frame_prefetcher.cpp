#include "crowdslam/run/frame_prefetcher.h"

#include <spdlog/spdlog.h>

#include "crowdslam/util/error.h"
#include "crowdslam/util/thread_priority.h"

namespace crowdslam::run {

FramePrefetcher::FramePrefetcher(io::FrameSource& source, size_t capacity, size_t max_frames,
                                 bool skip_bad_frames, Prepare prepare)
    : source_(source),
      capacity_(std::max<size_t>(1, capacity)),
      max_frames_(max_frames),
      skip_bad_frames_(skip_bad_frames && dynamic_cast<io::Dataset*>(&source) != nullptr),
      prepare_(std::move(prepare)) {
  reader_ = std::thread([this] {
    util::set_thread_name("cs-reader");
    run();
  });
}

FramePrefetcher::~FramePrefetcher() {
  cancel();
  if (reader_.joinable()) reader_.join();
}

void FramePrefetcher::cancel() {
  {
    std::lock_guard lock(mutex_);
    cancelled_ = true;
  }
  not_full_.notify_all();
}

SkippedFrames FramePrefetcher::skipped() const {
  std::lock_guard lock(mutex_);
  return skipped_;
}

void FramePrefetcher::run() {
  size_t produced = 0;
  while (max_frames_ == 0 || produced < max_frames_) {
    {
      std::unique_lock lock(mutex_);
      not_full_.wait(lock, [this] { return cancelled_ || queue_.size() < capacity_; });
      if (cancelled_) break;
    }
    std::optional<io::Frame> frame;
    try {
      frame = source_.next();
    } catch (const InputError& e) {
      std::lock_guard lock(mutex_);
      if (skip_bad_frames_) {
        if (skipped_.count++ == 0) {
          skipped_.first_error = e.what();
          spdlog::warn("skipping a frame that cannot be read (--skip-bad-frames): {}", e.what());
        }
        continue;
      }
      error_ = std::current_exception();
      break;
    } catch (...) {
      std::lock_guard lock(mutex_);
      error_ = std::current_exception();
      break;
    }
    if (!frame) break;
    std::shared_ptr<const system::PreparedFrame> prepared;
    if (prepare_) {
      try {
        prepared = prepare_(frame->images);
      } catch (...) {
        std::lock_guard lock(mutex_);
        error_ = std::current_exception();
        break;
      }
    }
    {
      std::lock_guard lock(mutex_);
      queue_.push_back(PrefetchedFrame{std::move(*frame), std::move(prepared)});
    }
    ++produced;
    not_empty_.notify_one();
  }
  {
    std::lock_guard lock(mutex_);
    finished_ = true;
  }
  not_empty_.notify_all();
}

std::optional<PrefetchedFrame> FramePrefetcher::next() {
  std::unique_lock lock(mutex_);
  not_empty_.wait(lock, [this] { return !queue_.empty() || finished_; });
  if (!queue_.empty()) {
    PrefetchedFrame frame = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    not_full_.notify_one();
    return frame;
  }
  if (error_) std::rethrow_exception(error_);
  return std::nullopt;
}

}  // namespace crowdslam::run
