#include "crowdslam/journal/run_journal.h"

#include "crowdslam/journal/frame_drawing.h"
#include "crowdslam/system/system.h"

namespace crowdslam::journal {

RunJournal::RunJournal(const RunJournalOptions& options) : options_(options) {
  JournalWriterOptions writer;
  writer.trajectory_path = options.out_dir / "CameraTrajectory.txt";
  writer.format = options.format;
  if (options.save_every > 0) writer.frames_dir = options.out_dir / "frames";
  writer.flush_every_poses = options.flush_every_poses;
  writer_ = std::make_unique<JournalWriter>(writer);
}

void RunJournal::on_frame(const system::FrameReport& report, const std::optional<geometry::SE3>& world_from_cam,
                          const io::FrameImages& images) {
  if (world_from_cam) writer_->append_pose({report.timestamp_s, *world_from_cam});
  if (options_.save_every > 0 && report.index % options_.save_every == 0) {
    // The image is shared (reference-counted), the keypoints copied: drawn on the writer thread.
    writer_->save_frame(report.index, [colour = images.colour, drawn = FrameDrawing::from(report)] {
      return drawn.draw(colour);
    });
  }
}

void RunJournal::on_finish(const system::EndState& /*end*/) { writer_->close(); }

}  // namespace crowdslam::journal
