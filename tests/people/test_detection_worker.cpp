// DetectionWorker: right frame back, blocking wait, exceptions, shutdown.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "crowdslam/people/detection_worker.h"

namespace crowdslam::people {
namespace {

using namespace std::chrono_literals;

// Returns one box whose x is the frame index and whose width is the image's first pixel value; sleeps
// `delay` first; throws on frame `throw_on`.
class FakeDetector : public PersonDetector {
 public:
  FakeDetector(std::chrono::milliseconds delay, std::size_t throw_on = SIZE_MAX)
      : delay_(delay), throw_on_(throw_on) {}
  Detections detect(const cv::Mat& bgr, std::size_t frame_index) override {
    started.store(true);
    std::this_thread::sleep_for(delay_);
    if (frame_index == throw_on_)
      throw std::runtime_error("fake failure on frame " + std::to_string(frame_index));
    Detections d;
    d.boxes.push_back({{static_cast<float>(frame_index), 0, static_cast<float>(bgr.at<uchar>(0, 0)), 1}, 1});
    calls.fetch_add(1);
    return d;
  }
  std::string name() const override { return "fake"; }
  std::atomic<int> calls{0};
  std::atomic<bool> started{false};

 private:
  std::chrono::milliseconds delay_;
  std::size_t throw_on_;
};

cv::Mat image_with(int value) { return cv::Mat(4, 4, CV_8UC1, cv::Scalar(value)); }

TEST(DetectionWorker, ResultsComeBackForTheRightFrame) {
  DetectionWorker worker(std::make_unique<FakeDetector>(0ms));
  for (std::size_t k = 0; k < 20; ++k) {
    worker.submit(k, image_with(static_cast<int>(k + 7)));
    const WorkerResult r = worker.wait(k);
    EXPECT_EQ(r.frame_index, k);
    ASSERT_EQ(r.detections.boxes.size(), 1u);
    EXPECT_FLOAT_EQ(r.detections.boxes[0].box.x, static_cast<float>(k));
    EXPECT_FLOAT_EQ(r.detections.boxes[0].box.width, static_cast<float>(k + 7));
  }
}

TEST(DetectionWorker, WaitBlocksUntilTheSlowDetectorIsDone) {
  DetectionWorker worker(std::make_unique<FakeDetector>(600ms));
  const auto start = std::chrono::steady_clock::now();
  worker.submit(3, image_with(1));
  const auto submitted = std::chrono::steady_clock::now();
  EXPECT_LT(submitted - start, 300ms);  // submit returns at once, long before the detection ends
  const WorkerResult r = worker.wait(3);
  const auto elapsed = std::chrono::steady_clock::now() - start;
  EXPECT_GE(elapsed, 600ms);
  EXPECT_GE(r.waited_ms, 300.0);
  EXPECT_EQ(r.detections.boxes.size(), 1u);
}

TEST(DetectionWorker, WaitAfterTheResultIsReadyDoesNotBlock) {
  auto detector = std::make_unique<FakeDetector>(0ms);
  FakeDetector* fake = detector.get();
  DetectionWorker worker(std::move(detector));
  worker.submit(0, image_with(1));
  while (fake->calls.load() == 0) std::this_thread::sleep_for(1ms);
  std::this_thread::sleep_for(20ms);
  EXPECT_LT(worker.wait(0).waited_ms,
            100.0);  // nothing to wait for (a loaded machine may deschedule us briefly)
}

TEST(DetectionWorker, DetectorExceptionReachesWaitAndWorkerStaysUsable) {
  DetectionWorker worker(std::make_unique<FakeDetector>(0ms, 1));
  worker.submit(0, image_with(1));
  EXPECT_EQ(worker.wait(0).detections.boxes.size(), 1u);
  worker.submit(1, image_with(1));
  try {
    worker.wait(1);
    FAIL() << "expected the detector's exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "fake failure on frame 1");
  }
  worker.submit(2, image_with(1));
  EXPECT_EQ(worker.wait(2).frame_index, 2u);
}

TEST(DetectionWorker, MisuseIsALogicError) {
  DetectionWorker worker(std::make_unique<FakeDetector>(50ms));
  EXPECT_THROW(worker.wait(0), std::logic_error);  // nothing submitted
  worker.submit(0, image_with(1));
  EXPECT_THROW(worker.submit(1, image_with(1)), std::logic_error);  // frame 0 still in flight
  EXPECT_THROW(worker.wait(5), std::logic_error);                   // not the submitted frame
  EXPECT_EQ(worker.wait(0).frame_index, 0u);
}

TEST(DetectionWorker, ShutdownWhileIdle) {
  const auto start = std::chrono::steady_clock::now();
  { DetectionWorker worker(std::make_unique<FakeDetector>(0ms)); }
  EXPECT_LT(std::chrono::steady_clock::now() - start, 1s);
}

TEST(DetectionWorker, ShutdownWhileADetectionIsRunning) {
  auto detector = std::make_unique<FakeDetector>(100ms);
  FakeDetector* fake = detector.get();
  const auto start = std::chrono::steady_clock::now();
  {
    DetectionWorker worker(std::move(detector));
    worker.submit(0, image_with(1));
    while (!fake->started.load()) std::this_thread::sleep_for(1ms);
  }  // destructor joins after the running detection
  EXPECT_GE(std::chrono::steady_clock::now() - start, 100ms);
}

TEST(DetectionWorker, ShutdownWithASubmittedFrameNeverCollected) {
  DetectionWorker worker(std::make_unique<FakeDetector>(10ms));
  worker.submit(0, image_with(1));
  // No wait(): the destructor must still return.
}

}  // namespace
}  // namespace crowdslam::people

namespace crowdslam::people {
namespace {

// Decoupled mode: offer() takes a frame only when the worker is free, poll() never blocks.
TEST(DetectionWorkerLatest, OfferTakesTheNewestFrameWhenFreeAndPollNeverBlocks) {
  auto detector = std::make_unique<FakeDetector>(600ms);
  DetectionWorker worker(std::move(detector));
  EXPECT_TRUE(worker.idle());
  EXPECT_FALSE(worker.poll().has_value());
  cv::Mat image = image_with(5);
  EXPECT_TRUE(worker.offer(0, image));
  image.setTo(99);  // offer() copied the pixels: the caller may reuse its buffer at once
  EXPECT_FALSE(worker.idle());
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(worker.offer(1, image_with(1)));  // busy: frame 1 is skipped
  EXPECT_FALSE(worker.poll().has_value());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 300ms);  // neither blocked on the 600 ms detection
  std::optional<WorkerResult> r;
  while (!(r = worker.poll())) std::this_thread::sleep_for(2ms);
  EXPECT_EQ(r->frame_index, 0u);
  ASSERT_EQ(r->detections.boxes.size(), 1u);
  EXPECT_FLOAT_EQ(r->detections.boxes[0].box.width, 5.0f);  // the pixels as offered, not as overwritten
  EXPECT_TRUE(worker.idle());
  EXPECT_TRUE(worker.offer(2, image_with(3)));
}

TEST(DetectionWorkerLatest, DetectorExceptionReachesPoll) {
  DetectionWorker worker(std::make_unique<FakeDetector>(0ms, 0));
  ASSERT_TRUE(worker.offer(0, image_with(1)));
  bool thrown = false;
  for (int i = 0; i < 5000 && !thrown; ++i) {
    try {
      if (!worker.poll()) std::this_thread::sleep_for(2ms);
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "fake failure on frame 0");
      thrown = true;
    }
  }
  EXPECT_TRUE(thrown);
  EXPECT_TRUE(worker.offer(1, image_with(1)));  // usable again
}

}  // namespace
}  // namespace crowdslam::people

namespace crowdslam::people {
namespace {

// Ahead of tracking: a reader thread submits frames as they are decoded, tracking collects each in
// its turn. Results are the frames' own, in order; frames never collected (a paced run's drops) are
// discarded; an exception reaches the frame it belongs to.
TEST(DetectionWorkerAhead, FramesSubmittedFromAnotherThreadComeBackInTheirTurn) {
  auto detector = std::make_unique<FakeDetector>(2ms);
  FakeDetector* fake = detector.get();
  DetectionWorker worker(std::move(detector));
  std::vector<std::size_t> tickets(30);
  std::thread reader([&] {
    for (std::size_t k = 0; k < tickets.size(); ++k)
      tickets[k] = worker.submit_ahead(k, image_with(int(k) + 1));
  });
  reader.join();
  for (std::size_t k = 0; k < tickets.size(); ++k) {
    EXPECT_EQ(tickets[k], k + 1);
    if (k % 3 == 2) continue;  // dropped: never collected
    const WorkerResult r = worker.wait_ahead(tickets[k]);
    EXPECT_EQ(r.frame_index, k);
    ASSERT_EQ(r.detections.boxes.size(), 1u);
    EXPECT_FLOAT_EQ(r.detections.boxes[0].box.x, static_cast<float>(k));
    EXPECT_FLOAT_EQ(r.detections.boxes[0].box.width, static_cast<float>(k + 1));
  }
  // A dropped frame's ticket is gone once a later one was collected; so is a collected one.
  EXPECT_THROW(worker.wait_ahead(tickets[2]), std::logic_error);
  EXPECT_THROW(worker.wait_ahead(tickets[0]), std::logic_error);
  EXPECT_THROW(worker.wait_ahead(tickets.size() + 5), std::logic_error);
  EXPECT_LE(fake->calls.load(), 30);
}

TEST(DetectionWorkerAhead, WaitBlocksUntilTheFramesTurnAndAnExceptionReachesItsFrame) {
  DetectionWorker worker(std::make_unique<FakeDetector>(150ms, 1));
  const std::size_t first = worker.submit_ahead(0, image_with(1));
  const std::size_t failing = worker.submit_ahead(1, image_with(1));
  const std::size_t third = worker.submit_ahead(2, image_with(9));
  const auto start = std::chrono::steady_clock::now();
  const WorkerResult r = worker.wait_ahead(first);
  EXPECT_GE(std::chrono::steady_clock::now() - start, 100ms);  // waited for its detection
  EXPECT_GT(r.waited_ms, 100.0);
  try {
    worker.wait_ahead(failing);
    FAIL() << "expected the detector's exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "fake failure on frame 1");
  }
  const WorkerResult after = worker.wait_ahead(third);  // the worker goes on after a failure
  ASSERT_EQ(after.detections.boxes.size(), 1u);
  EXPECT_FLOAT_EQ(after.detections.boxes[0].box.width, 9.0f);
}

TEST(DetectionWorkerAhead, ShutdownWithFramesQueuedAndNeverCollected) {
  const auto start = std::chrono::steady_clock::now();
  {
    DetectionWorker worker(std::make_unique<FakeDetector>(50ms));
    for (std::size_t k = 0; k < 10; ++k) worker.submit_ahead(k, image_with(1));
  }  // the destructor drops the queue: at most the running detection is finished
  EXPECT_LT(std::chrono::steady_clock::now() - start, 300ms);
}

}  // namespace
}  // namespace crowdslam::people
