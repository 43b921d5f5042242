#pragma once
// Reads frames from a FrameSource on a background thread into a small bounded queue, so that image
// decoding overlaps with tracking. End of stream and reader errors are delivered in order: next()
// returns nullopt at the end, and rethrows the reader's exception at the point where it happened.
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "crowdslam/io/dataset.h"

namespace crowdslam::system {

class FramePrefetcher {
 public:
  // `source` must outlive the prefetcher. max_frames 0 = all.
  FramePrefetcher(io::FrameSource& source, size_t capacity = 3, size_t max_frames = 0);
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  std::optional<io::Frame> next();

 private:
  void run();

  io::FrameSource& source_;
  const size_t capacity_;
  const size_t max_frames_;
  std::mutex mutex_;
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::deque<io::Frame> queue_;
  bool finished_ = false;  // reader reached the end (or failed)
  bool cancelled_ = false;
  std::exception_ptr error_;
  std::thread reader_;
};

}  // namespace crowdslam::system
