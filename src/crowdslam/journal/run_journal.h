#pragma once
// The output journal: a RunObserver that keeps the run's work on disk while it runs.
//   OUT/CameraTrajectory.txt  appended as frames are tracked (pose at tracking time), flushed every few
//                             frames; replaced at the end by the refined trajectory (run/run_sequence)
//   OUT/frames/NNNNNN.jpg     with save_every N: every N-th frame, drawn and written as it comes
// Work is done by a JournalWriter thread; the observer calls only copy what they need and queue it.
#include <filesystem>
#include <memory>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/journal/journal_writer.h"
#include "crowdslam/system/run_observer.h"

namespace crowdslam::journal {

struct RunJournalOptions {
  std::filesystem::path out_dir;
  io::TrajectoryFormat format = io::TrajectoryFormat::kTum;
  size_t save_every = 0;  // --save-frames N (0 = none)
  size_t flush_every_poses = 10;
};

class RunJournal : public system::RunObserver {
 public:
  explicit RunJournal(const RunJournalOptions& options);
  void on_frame(const system::FrameReport& report, const std::optional<geometry::SE3>& world_from_cam,
                const io::FrameImages& images) override;
  void on_finish(const system::EndState& end) override;

  // Rethrows a write error of the journal (call once per frame from the run loop).
  void check() const { writer_->check(); }
  // Drains and closes the journal (on_finish does it; also safe to call on error paths).
  void close() { writer_->close(); }
  [[nodiscard]] JournalWriterStats stats() const { return writer_->stats(); }

 private:
  RunJournalOptions options_;
  std::unique_ptr<JournalWriter> writer_;
};

}  // namespace crowdslam::journal
