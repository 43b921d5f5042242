#pragma once
// The journal writer thread: appends the trajectory to OUT/CameraTrajectory.txt as frames are tracked
// and writes saved frames (OUT/frames/NNNNNN.jpg) as they are drawn, off the tracking thread.
//
// - Poses are never dropped: their queue is unbounded (a line each). Lines are written to the OS in one
//   write() every `flush_every_poses` poses and at close(), so a process killed at any moment leaves a
//   trajectory that ends at most that many poses early. A failed or short write (disk full) is cut back
//   to the last complete line, so the file never ends in half a line.
// - Saved frames wait in a bounded queue (`frame_queue_capacity`); when it is full save_frame() blocks
//   until the writer has caught up, so memory stays bounded and no frame is silently dropped.
// - A write error (disk full, file removed, ...) stops the writer; check() rethrows it on the caller's
//   thread as an InputError naming the file.
// Thread-safe: any thread may call append_pose / save_frame / check / close.
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <thread>

#include "crowdslam/io/trajectory.h"

namespace crowdslam::journal {

struct JournalWriterOptions {
  std::filesystem::path trajectory_path;  // the journal (truncated on open; header written first)
  io::TrajectoryFormat format = io::TrajectoryFormat::kTum;
  std::filesystem::path frames_dir;       // empty: no saved frames
  size_t flush_every_poses = 10;
  size_t frame_queue_capacity = 4;
  int jpeg_quality = 90;
};

struct JournalWriterStats {
  size_t poses_written = 0;
  size_t frames_saved = 0;
  size_t frame_waits = 0;  // save_frame() calls that waited for a free place in the queue
};

class JournalWriter {
 public:
  // Opens the journal file; throws InputError naming it when it cannot.
  explicit JournalWriter(JournalWriterOptions options);
  ~JournalWriter();
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;

  void append_pose(const io::StampedPose& pose);
  // `draw` runs on the writer thread and returns the image to encode as frames/NNNNNN.jpg.
  void save_frame(size_t index, std::function<cv::Mat()> draw);
  // Writes everything queued, flushes and closes the journal, stops the thread (idempotent).
  void close();
  // Rethrows the first write error.
  void check() const;
  [[nodiscard]] JournalWriterStats stats() const;

 private:
  struct Task {
    bool is_frame = false;
    io::StampedPose pose;
    size_t index = 0;
    std::function<cv::Mat()> draw;
  };
  void run();
  void write_pose(const io::StampedPose& pose);
  void write_frame(size_t index, const std::function<cv::Mat()>& draw);
  void fail(const std::string& file, const std::string& message);

  JournalWriterOptions options_;
  // Writer thread only (and close() after joining it).
  bool flush_pending();
  int fd_ = -1;
  std::string pending_;    // complete lines not yet written
  size_t unflushed_ = 0;   // poses in pending_
  long long written_bytes_ = 0;  // file size after the last complete write

  mutable std::mutex mutex_;
  std::condition_variable work_cv_;
  std::condition_variable space_cv_;
  std::deque<Task> tasks_;
  size_t queued_frames_ = 0;
  bool closing_ = false;
  bool closed_ = false;
  std::exception_ptr error_;
  JournalWriterStats stats_;
  std::thread thread_;  // last: started after every other member is initialised
};

}  // namespace crowdslam::journal
