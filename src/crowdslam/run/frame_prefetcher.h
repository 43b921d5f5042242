#pragma once
// Reads frames from a FrameSource on a background thread into a small bounded queue, so that image
// decoding overlaps with tracking. With a `prepare` function the same thread also starts each frame's
// work that does not wait for its turn (System::prepare: the budget-independent part of its ORB
// extraction here, its person detection on the detector's thread). End of stream and reader errors are
// delivered in order: next() returns nullopt at the end, and rethrows the reader's exception at the point
// where it happened.
//
// With `skip_bad_frames`, an InputError for one frame of a dataset on disk (which can go on to the next
// frame) is counted and the frame skipped instead; videos and cameras still stop at an error.
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "crowdslam/io/dataset.h"
#include "crowdslam/system/system.h"

namespace crowdslam::run {

struct SkippedFrames {
  size_t count = 0;
  std::string first_error;  // the first skipped frame's error (names the file)
};

struct PrefetchedFrame {
  io::Frame frame;
  std::shared_ptr<const system::PreparedFrame> prepared;  // null without a prepare function, or refused
};

class FramePrefetcher {
 public:
  using Prepare = std::function<std::shared_ptr<const system::PreparedFrame>(const io::FrameImages&)>;
  // `source` (and what `prepare` uses) must outlive the prefetcher. max_frames 0 = all.
  FramePrefetcher(io::FrameSource& source, size_t capacity = 3, size_t max_frames = 0,
                  bool skip_bad_frames = false, Prepare prepare = {});
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  std::optional<PrefetchedFrame> next();
  // Stops reading ahead (interrupts); next() then returns what is queued, then nullopt.
  void cancel();
  [[nodiscard]] SkippedFrames skipped() const;

 private:
  void run();

  io::FrameSource& source_;
  const size_t capacity_;
  const size_t max_frames_;
  const bool skip_bad_frames_;
  const Prepare prepare_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::deque<PrefetchedFrame> queue_;
  bool finished_ = false;  // reader reached the end (or failed)
  bool cancelled_ = false;
  std::exception_ptr error_;
  SkippedFrames skipped_;
  std::thread reader_;
};

}  // namespace crowdslam::run
