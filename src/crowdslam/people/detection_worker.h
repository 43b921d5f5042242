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
// Thread safety: submit() and wait() are meant for one caller thread (tracking); all state shared with the
// worker thread is guarded by one mutex.
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <memory>
#include <mutex>
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

  [[nodiscard]] const PersonDetector& detector() const { return *detector_; }

 private:
  enum class State { kIdle, kPending, kRunning, kDone };

  void run();

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
  std::thread thread_;  // last: started after every other member is initialised
};

}  // namespace crowdslam::people
