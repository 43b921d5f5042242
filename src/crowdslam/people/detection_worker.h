#pragma once
// Runs a PersonDetector on its own thread, one frame at a time, so detection overlaps ORB extraction:
//
//   worker.submit(k, colour);   // returns at once
//   ... extract ORB features of frame k ...
//   WorkerResult r = worker.wait(k);  // blocks (condition variable) until frame k's boxes are ready
//
// At most one frame is in flight: submit() while a frame has not been collected by wait() is a
// programming error (std::logic_error), as is wait() for a frame that was not submitted. The worker keeps
// a reference to the submitted image (no copy): do not write into its pixels until wait() returns.
// An exception thrown by the detector is rethrown by wait(). The destructor stops and joins the thread;
// a detection that is running is finished first (a forward pass cannot be interrupted), a submitted
// frame that has not started is dropped.
//
// Decoupled use (Detector.mode: latest), so a slow detector never holds tracking up:
//
//   if (worker.idle()) worker.offer(k, colour);   // the worker copies the image and starts on it
//   if (auto r = worker.poll()) ...               // a finished result (of an earlier frame), or nothing
//
// offer() returns false (and does nothing) while a frame is in flight or its result was not collected.
//
// Ahead of tracking (every_frame mode fed by the thread that reads the frames):
//
//   ticket = worker.submit_ahead(k, colour);   // reader thread, as soon as frame k is decoded
//   ...
//   WorkerResult r = worker.wait_ahead(ticket);  // tracking thread, in the frame's turn
//
// Frames submitted ahead are detected in submission order (after a submit()/offer() frame in flight),
// each result kept until its ticket is collected; collecting a ticket discards the results of earlier
// tickets never collected (frames a paced run dropped). submit_ahead() may be called from one other
// thread than the rest.
//
// Thread safety: submit(), wait(), offer() and poll() are meant for one caller thread (tracking); all state
// shared with the worker thread is guarded by one mutex.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

struct WorkerResult {
  std::size_t frame_index = 0;
  Detections detections;
  double waited_ms = 0.0;  // how long wait() blocked (0 when the result was already there)
};

class DetectionWorker {
 public:
  explicit DetectionWorker(std::unique_ptr<PersonDetector> detector);
  ~DetectionWorker();
  DetectionWorker(const DetectionWorker&) = delete;
  DetectionWorker& operator=(const DetectionWorker&) = delete;

  void submit(std::size_t frame_index, cv::Mat bgr);
  WorkerResult wait(std::size_t frame_index);
  // Decoupled mode: starts on a copy of `bgr` when no frame is in flight; false when busy.
  bool offer(std::size_t frame_index, const cv::Mat& bgr);
  // The finished result, if there is one (never blocks); rethrows the detector's exception.
  std::optional<WorkerResult> poll();
  // No frame in flight and no result waiting: offer() would start.
  [[nodiscard]] bool idle();
  // Queues `bgr` (kept by reference, not copied) for detection; returns its ticket (1, 2, ...).
  std::size_t submit_ahead(std::size_t frame_index, cv::Mat bgr);
  // Blocks until the ticket's result is ready; rethrows the detector's exception for that frame; a
  // ticket never issued, or already collected or discarded, is a std::logic_error.
  WorkerResult wait_ahead(std::size_t ticket);

  [[nodiscard]] const PersonDetector& detector() const { return *detector_; }

 private:
  enum class State { kIdle, kPending, kRunning, kDone };
  struct AheadJob {
    std::size_t ticket = 0;
    std::size_t frame_index = 0;
    cv::Mat image;
  };
  struct AheadResult {
    std::size_t frame_index = 0;
    Detections detections;
    std::exception_ptr error;
  };

  void run();
  // The finished result (state kDone, mutex held); rethrows the detector's exception. Back to kIdle.
  WorkerResult take_result();

  std::unique_ptr<PersonDetector> detector_;
  std::mutex mutex_;
  std::condition_variable wake_worker_;
  std::condition_variable result_ready_;
  State state_ = State::kIdle;
  bool stop_ = false;
  std::size_t frame_index_ = 0;
  cv::Mat image_;
  Detections result_;
  std::exception_ptr error_;
  std::deque<AheadJob> ahead_queue_;
  std::map<std::size_t, AheadResult> ahead_results_;
  std::size_t last_ticket_ = 0;       // issued
  std::size_t collected_ticket_ = 0;  // tickets up to this one are collected or discarded
  std::thread thread_;  // last: started after every other member is initialised
};

}  // namespace crowdslam::people
