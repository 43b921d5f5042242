#include "crowdslam/people/detection_worker.h"

#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>

#include "crowdslam/util/thread_priority.h"

namespace crowdslam::people {

DetectionWorker::DetectionWorker(std::unique_ptr<PersonDetector> detector)
    : detector_(std::move(detector)), thread_([this] {
        util::set_thread_name("cs-detector");
        run();
      }) {}

DetectionWorker::~DetectionWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_worker_.notify_all();
  thread_.join();
}

void DetectionWorker::submit(std::size_t frame_index, cv::Mat bgr) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (state_ != State::kIdle)
      throw std::logic_error("DetectionWorker::submit(" + std::to_string(frame_index) + "): frame " +
                             std::to_string(frame_index_) + " is still in flight");
    frame_index_ = frame_index;
    image_ = std::move(bgr);
    error_ = nullptr;
    state_ = State::kPending;
  }
  wake_worker_.notify_one();
}

WorkerResult DetectionWorker::wait(std::size_t frame_index) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  if (state_ == State::kIdle || frame_index_ != frame_index)
    throw std::logic_error("DetectionWorker::wait(" + std::to_string(frame_index) + "): frame not submitted");
  result_ready_.wait(lock, [this] { return state_ == State::kDone; });
  WorkerResult out = take_result();
  out.waited_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

WorkerResult DetectionWorker::take_result() {
  WorkerResult out;
  out.frame_index = frame_index_;
  state_ = State::kIdle;
  image_.release();
  if (error_) {
    std::exception_ptr error = std::exchange(error_, nullptr);
    std::rethrow_exception(error);
  }
  out.detections = std::move(result_);
  result_ = {};
  return out;
}

std::size_t DetectionWorker::submit_ahead(std::size_t frame_index, cv::Mat bgr) {
  std::size_t ticket = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ticket = ++last_ticket_;
    ahead_queue_.push_back(AheadJob{ticket, frame_index, std::move(bgr)});
  }
  wake_worker_.notify_one();
  return ticket;
}

WorkerResult DetectionWorker::wait_ahead(std::size_t ticket) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  if (ticket == 0 || ticket > last_ticket_ || ticket <= collected_ticket_)
    throw std::logic_error("DetectionWorker::wait_ahead(" + std::to_string(ticket) +
                           "): no such ticket in flight");
  result_ready_.wait(lock, [&] { return ahead_results_.count(ticket) > 0; });
  AheadResult result = std::move(ahead_results_.at(ticket));
  // This ticket and every earlier one are done with: their frames were collected or dropped.
  ahead_results_.erase(ahead_results_.begin(), ahead_results_.upper_bound(ticket));
  collected_ticket_ = ticket;
  lock.unlock();
  if (result.error) std::rethrow_exception(result.error);
  WorkerResult out;
  out.frame_index = result.frame_index;
  out.detections = std::move(result.detections);
  out.waited_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

bool DetectionWorker::offer(std::size_t frame_index, const cv::Mat& bgr) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (state_ != State::kIdle) return false;
    frame_index_ = frame_index;
    image_ = bgr.clone();  // the caller does not wait for the result, so it may reuse its buffer
    error_ = nullptr;
    state_ = State::kPending;
  }
  wake_worker_.notify_one();
  return true;
}

bool DetectionWorker::idle() {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_ == State::kIdle;
}

std::optional<WorkerResult> DetectionWorker::poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (state_ != State::kDone) return std::nullopt;
  return take_result();
}

void DetectionWorker::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_worker_.wait(lock, [this] { return stop_ || state_ == State::kPending || !ahead_queue_.empty(); });
    if (stop_) return;
    if (state_ != State::kPending) {
      AheadJob job = std::move(ahead_queue_.front());
      ahead_queue_.pop_front();
      if (job.ticket <= collected_ticket_) continue;  // its frame was dropped and a later one collected
      lock.unlock();
      AheadResult result;
      result.frame_index = job.frame_index;
      try {
        result.detections = detector_->detect(job.image, job.frame_index);
      } catch (...) {
        result.error = std::current_exception();
      }
      job.image.release();
      lock.lock();
      if (job.ticket > collected_ticket_) ahead_results_.emplace(job.ticket, std::move(result));
      result_ready_.notify_all();
      continue;
    }
    state_ = State::kRunning;
    const cv::Mat image = image_;
    const std::size_t frame_index = frame_index_;
    lock.unlock();
    Detections detections;
    std::exception_ptr error;
    try {
      detections = detector_->detect(image, frame_index);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    result_ = std::move(detections);
    error_ = error;
    state_ = State::kDone;
    result_ready_.notify_all();
  }
}

}  // namespace crowdslam::people
