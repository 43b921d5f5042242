// System::prepare: a frame's budget-independent ORB work and its person detection started on another
// thread before track() (as `crowdslam run`'s reader thread does) change nothing in what tracking does:
// the same keypoints, boxes and poses, frame by frame, as track() alone.
#include <gtest/gtest.h>

#include <deque>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/system/system.h"
#include "test_support.h"

using namespace crowdslam;

namespace {
struct FrameOutcome {
  int keypoints = 0;
  int keypoints_before_filter = 0;
  int person_boxes = 0;
  double people_area = 0;
  int tracked_points = 0;
};

struct Outcome {
  std::vector<FrameOutcome> frames;
  std::vector<io::StampedPose> trajectory;
  int frames_prepared = 0;
  int detections_ahead = 0;
};

Outcome run(const std::filesystem::path& seq, io::SensorKind sensor, bool ahead) {
  auto dataset = io::open_dataset(seq.string());
  const io::Settings settings = io::load_settings((seq / "settings.yaml").string(), sensor);
  system::SystemOptions options;
  options.sensor = sensor;
  options.sequential = true;  // mapping inline: the same map whatever the threads' timing
  options.vocabulary_path = "none";
  options.loop_closing = false;
  system::System slam(settings, options);
  std::vector<io::Frame> frames;
  while (auto frame = dataset->next()) frames.push_back(std::move(*frame));
  // The reader's side: every frame prepared on another thread before its turn (all of them, here).
  std::vector<std::shared_ptr<const system::PreparedFrame>> prepared(frames.size());
  if (ahead) {
    std::thread reader([&] {
      for (size_t i = 0; i < frames.size(); ++i) prepared[i] = slam.prepare(frames[i].images);
    });
    reader.join();
  }
  Outcome o;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (prepared[i]) {
      ++o.frames_prepared;
      if (prepared[i]->detection_ticket) ++o.detections_ahead;
    }
    const auto r = slam.track(frames[i].images, frames[i].info.timestamp_s, prepared[i].get());
    o.frames.push_back(
        {r.keypoints, r.keypoints_before_filter, r.person_boxes, r.people_area, r.tracked_points});
  }
  slam.shutdown();
  o.trajectory = slam.camera_trajectory();
  return o;
}

void expect_same(const Outcome& a, const Outcome& b) {
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(a.frames[i].keypoints_before_filter, b.frames[i].keypoints_before_filter) << "frame " << i;
    EXPECT_EQ(a.frames[i].keypoints, b.frames[i].keypoints) << "frame " << i;
    EXPECT_EQ(a.frames[i].person_boxes, b.frames[i].person_boxes) << "frame " << i;
    EXPECT_EQ(a.frames[i].people_area, b.frames[i].people_area) << "frame " << i;
    EXPECT_EQ(a.frames[i].tracked_points, b.frames[i].tracked_points) << "frame " << i;
  }
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (size_t i = 0; i < a.trajectory.size(); ++i) {
    EXPECT_EQ(a.trajectory[i].world_from_cam.matrix(), b.trajectory[i].world_from_cam.matrix())
        << "pose " << i;
  }
}
}  // namespace

void check_sequence(const std::filesystem::path& seq, io::SensorKind sensor, int frames, int prepared) {
  const Outcome plain = run(seq, sensor, false);
  const Outcome ahead = run(seq, sensor, true);
  EXPECT_EQ(ahead.frames_prepared, prepared);
  EXPECT_EQ(ahead.detections_ahead, prepared);  // every prepared frame's detection started before its turn
  int frames_with_people = 0;
  for (const auto& f : plain.frames) frames_with_people += f.person_boxes > 0 ? 1 : 0;
  EXPECT_GE(frames_with_people, 5);  // the detector sees people, so there are boxes to compare
  EXPECT_GT(plain.trajectory.size(), static_cast<size_t>(frames / 2));
  expect_same(plain, ahead);
}

TEST(PrepareAhead, RgbdAndMonocularCrowdsTrackExactlyAsWithoutIt) {
  const auto models = test::shared_dir() / "models" / "yolo-fastest-1.1";
  if (!std::filesystem::exists(models)) GTEST_SKIP() << "shared models missing: " << models;
  test::TempDir tmp;
  synth::SynthOptions crowd;
  crowd.frames = 40;
  crowd.people = 8;
  crowd.seed = 5;
  synth::write_sequence(crowd, tmp / "crowd");
  {
    SCOPED_TRACE("RGB-D, 8 people");
    check_sequence(tmp / "crowd", io::SensorKind::kRgbd, crowd.frames, crowd.frames);
  }
  synth::SynthOptions room;  // monocular needs a longer, emptier start to initialise
  room.frames = 90;
  room.people = 3;
  room.seed = 1;
  synth::write_sequence(room, tmp / "room");
  {
    SCOPED_TRACE("monocular, 3 people: not prepared ahead (System::prepare), tracked as without");
    check_sequence(tmp / "room", io::SensorKind::kMonocular, room.frames, 0);
  }
}
