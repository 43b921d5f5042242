// JournalWriter: the trajectory journal appended line by line off the tracking thread, saved frames with
// bounded memory, and write errors (a full disk: /dev/full) reported to the caller, never half a line.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/journal/journal_writer.h"
#include "test_support.h"

using crowdslam::journal::JournalWriter;
using crowdslam::journal::JournalWriterOptions;
using crowdslam::test::TempDir;
namespace fs = std::filesystem;

namespace {
crowdslam::io::StampedPose pose_at(double t) {
  crowdslam::io::StampedPose p;
  p.timestamp_s = t;
  p.world_from_cam = crowdslam::geometry::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * t, Eigen::Vector3d::UnitZ())),
                                              Eigen::Vector3d(t, 2 * t, -t));
  return p;
}
}  // namespace

TEST(JournalWriter, PosesReadBackAsTheTrajectoryWrittenInOneGo) {
  TempDir dir;
  JournalWriterOptions options;
  options.trajectory_path = dir / "journal.txt";
  options.flush_every_poses = 7;
  crowdslam::io::Trajectory expected;
  {
    JournalWriter writer(options);
    for (int i = 0; i < 50; ++i) {
      expected.push_back(pose_at(0.1 * i));
      writer.append_pose(expected.back());
    }
    writer.close();
    writer.check();
    EXPECT_EQ(writer.stats().poses_written, 50u);
  }
  crowdslam::io::write_tum_trajectory((dir / "whole.txt").string(), expected);
  EXPECT_EQ(crowdslam::test::read_text(dir / "journal.txt"), crowdslam::test::read_text(dir / "whole.txt"));
}

TEST(JournalWriter, FlushesEveryNPosesWhileRunning) {
  TempDir dir;
  JournalWriterOptions options;
  options.trajectory_path = dir / "journal.txt";
  options.flush_every_poses = 5;
  JournalWriter writer(options);
  for (int i = 0; i < 12; ++i) writer.append_pose(pose_at(i));
  // Before close: the two complete batches of 5 are on disk (the writer thread gets to them).
  size_t lines = 0;
  for (int attempt = 0; attempt < 400 && lines < 10; ++attempt) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const auto text = crowdslam::test::read_text(dir / "journal.txt");
    lines = static_cast<size_t>(std::count(text.begin(), text.end(), '\n')) - 1;  // minus the header
  }
  EXPECT_EQ(lines, 10u);
  writer.close();
  const auto text = crowdslam::test::read_text(dir / "journal.txt");
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 13);
}

TEST(JournalWriter, FullDiskIsReportedNamingTheFile) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  JournalWriterOptions options;
  options.trajectory_path = "/dev/full";
  options.format = crowdslam::io::TrajectoryFormat::kKitti;  // no header: the first flush fails
  options.flush_every_poses = 2;
  JournalWriter writer(options);
  for (int i = 0; i < 10; ++i) writer.append_pose(pose_at(i));
  writer.close();
  const std::string message = crowdslam::test::error_of([&] { writer.check(); });
  EXPECT_NE(message.find("/dev/full"), std::string::npos) << message;
  EXPECT_NE(message.find("No space left"), std::string::npos) << message;
}

TEST(JournalWriter, SavedFramesAreBoundedAndAllWritten) {
  TempDir dir;
  JournalWriterOptions options;
  options.trajectory_path = dir / "journal.txt";
  options.frames_dir = dir / "frames";
  options.frame_queue_capacity = 2;
  std::atomic<int> in_flight{0};
  std::atomic<int> max_in_flight{0};
  {
    JournalWriter writer(options);
    for (size_t i = 0; i < 20; ++i) {
      const int now = ++in_flight;
      max_in_flight = std::max(max_in_flight.load(), now);
      writer.save_frame(i, [&in_flight, i] {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        --in_flight;
        return cv::Mat(48, 64, CV_8UC3, cv::Scalar(static_cast<double>(i), 0, 0));
      });
    }
    writer.close();
    writer.check();
    EXPECT_EQ(writer.stats().frames_saved, 20u);
    EXPECT_GT(writer.stats().frame_waits, 0u);
  }
  // At most the queue's capacity waited, plus the one being drawn.
  EXPECT_LE(max_in_flight.load(), 3);
  for (size_t i = 0; i < 20; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.jpg", i);
    const cv::Mat image = cv::imread((dir / "frames" / name).string());
    ASSERT_FALSE(image.empty()) << name;
    EXPECT_EQ(image.cols, 64);
  }
}

TEST(JournalWriter, UnwritableJournalIsAnErrorAtOnce) {
  TempDir dir;
  JournalWriterOptions options;
  options.trajectory_path = dir / "no_such_dir" / "journal.txt";
  const std::string message = crowdslam::test::error_of([&] { JournalWriter writer(options); });
  EXPECT_NE(message.find("no_such_dir"), std::string::npos) << message;
}
