// Backpressure (issue 11): in the default threaded mode, when tracking needs a keyframe urgently and
// local mapping is behind, tracking waits for the mapper (bounded, with the map unlocked) instead of
// tracking on without new map points. Checked with an artificially slow mapper (SystemOptions::
// mapper_delay_ms) on a monocular sweep through the synthetic room: with waiting, every frame from the
// initialisation on is tracked and some frames record the wait; without it (max wait 0, ORB-SLAM2's
// behaviour) the same slow mapper costs keyframes.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/system/system.h"
#include "test_support.h"

using namespace crowdslam;

namespace {
struct Outcome {
  size_t frames = 0;
  size_t tracked = 0;
  size_t keyframes = 0;
  int frames_waited = 0;
  double waited_ms = 0;
  int resets = 0;
  std::optional<size_t> init_frame;
  size_t localized_before_init = 0;  // frames before the initialisation given a pose by it (reference included)
  io::Trajectory trajectory;
};

// The synthetic room swept by a monocular camera: 90 frames at 320 x 240, no people.
void write_sweep(const std::filesystem::path& seq) {
  synth::SynthOptions synth_options;
  synth_options.frames = 90;
  synth_options.width = 320;
  synth_options.height = 240;
  synth_options.trajectory = synth::TrajectoryKind::kSweep;
  synth_options.people = 0;
  synth::write_sequence(synth_options, seq);
}

Outcome run(const std::filesystem::path& seq, double max_wait_ms, double mapper_delay_ms) {
  auto dataset = io::open_dataset(seq.string());
  const io::Settings settings = io::load_settings((seq / "settings.yaml").string(), io::SensorKind::kMonocular);
  system::SystemOptions options;
  options.sensor = io::SensorKind::kMonocular;
  options.people_filter = false;
  options.vocabulary_path = "none";
  options.loop_closing = false;
  options.max_wait_for_mapping_ms = max_wait_ms;
  options.mapper_delay_ms = mapper_delay_ms;
  system::System slam(settings, options);
  Outcome o;
  while (auto frame = dataset->next()) {
    const auto r = slam.track(frame->images, frame->info.timestamp_s);
    ++o.frames;
    if (!o.init_frame && r.method == std::string("init")) o.init_frame = r.index;
    if (r.waited_for_mapping_ms > 0) ++o.frames_waited;
    o.localized_before_init += r.localized_before_init.size();
    o.waited_ms += r.waited_for_mapping_ms;
  }
  slam.shutdown();
  o.tracked = slam.tracked_frames();
  o.trajectory = slam.camera_trajectory();
  o.keyframes = slam.keyframe_trajectory().size();
  o.resets = slam.map_resets();
  return o;
}
}  // namespace

TEST(Backpressure, SlowMapperMakesTrackingWaitInsteadOfGoingOnWithoutKeyframes) {
  test::TempDir tmp;
  write_sweep(tmp / "seq");

  const Outcome waiting = run(tmp / "seq", 1000.0, 120.0);
  const Outcome ignoring = run(tmp / "seq", 0.0, 120.0);
  std::printf("[ measured ] mapper +120 ms/keyframe: waiting %zu/%zu tracked, %zu keyframes, %d frames waited "
              "(%.0f ms); not waiting %zu/%zu tracked, %zu keyframes, %d resets\n",
              waiting.tracked, waiting.frames, waiting.keyframes, waiting.frames_waited, waiting.waited_ms,
              ignoring.tracked, ignoring.frames, ignoring.keyframes, ignoring.resets);
  ASSERT_TRUE(waiting.init_frame.has_value());
  EXPECT_EQ(waiting.resets, 0);
  // Every frame from the initialisation on, and those before it that the new map localised: at least the
  // initialisation's reference frame (the first keyframe).
  EXPECT_GE(waiting.localized_before_init, 1u);
  EXPECT_EQ(waiting.tracked, waiting.frames - *waiting.init_frame + waiting.localized_before_init);
  EXPECT_GT(waiting.frames_waited, 0);
  EXPECT_EQ(ignoring.frames_waited, 0);
  EXPECT_GT(waiting.keyframes, ignoring.keyframes);  // without waiting the slow mapper cost keyframes
}

// An unpaced monocular replay tracks each frame after a keyframe once the mapper has mapped it (new points
// and local BA), and localises the frames before the initialisation in the map as the mapper leaves it, so
// its trajectory does not depend on how fast the mapper is: a mapper slowed by 15 ms a keyframe gives the
// same poses, bit for bit. Before, the frame after a keyframe raced the keyframe's local BA and the runs
// differed by millimetres to (in crowds) a collapsed scale.
TEST(Backpressure, UnpacedMonocularReplayGivesTheSameTrajectoryOnEveryRun) {
  test::TempDir tmp;
  write_sweep(tmp / "seq");

  const Outcome fast = run(tmp / "seq", 1000.0, 0.0);
  const Outcome slow = run(tmp / "seq", 1000.0, 15.0);
  ASSERT_TRUE(fast.init_frame.has_value());
  EXPECT_GT(fast.frames_waited, 0);
  EXPECT_GE(fast.localized_before_init, 1u);
  ASSERT_GT(fast.trajectory.size(), fast.frames / 2);
  ASSERT_EQ(fast.trajectory.size(), slow.trajectory.size());
  for (size_t i = 0; i < fast.trajectory.size(); ++i) {
    const auto& a = fast.trajectory[i];
    const auto& b = slow.trajectory[i];
    ASSERT_EQ(a.timestamp_s, b.timestamp_s) << "pose " << i;
    EXPECT_EQ(a.world_from_cam.translation(), b.world_from_cam.translation()) << "pose " << i;
    EXPECT_EQ(a.world_from_cam.rotation().coeffs(), b.world_from_cam.rotation().coeffs()) << "pose " << i;
  }
}

// Local mapping runs SystemOptions::background_nice nicer than tracking (util/thread_priority.h): the
// named thread's nice value, read from /proc while the system runs.
namespace {
// Nice value of this process's thread named `name` (-100 if there is none): field 19 of
// /proc/self/task/TID/stat, counted after the command name's closing parenthesis.
int nice_of_thread(const std::string& name) {
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string task_name;
    std::getline(comm, task_name);
    if (task_name != name) continue;
    std::ifstream stat(task.path() / "stat");
    const std::string line((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    std::istringstream rest(line.substr(line.rfind(')') + 2));
    std::string field;
    for (int i = 3; i <= 19 && rest >> field; ++i) {
    }
    return std::stoi(field);
  }
  return -100;
}

int mapper_nice(const std::filesystem::path& seq, int background_nice) {
  auto dataset = io::open_dataset(seq.string());
  const io::Settings settings = io::load_settings((seq / "settings.yaml").string(), io::SensorKind::kRgbd);
  system::SystemOptions options;
  options.people_filter = false;
  options.vocabulary_path = "none";
  options.loop_closing = false;
  options.background_nice = background_nice;
  system::System slam(settings, options);
  for (int i = 0; i < 3; ++i) {
    auto frame = dataset->next();
    slam.track(frame->images, frame->info.timestamp_s);
  }
  // The mapper thread names itself when it starts: wait for it (a loaded machine may start it late).
  int nice = nice_of_thread("cs-mapper");
  for (int i = 0; i < 500 && nice == -100; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    nice = nice_of_thread("cs-mapper");
  }
  slam.shutdown();
  return nice;
}
}  // namespace

TEST(BackgroundThreads, LocalMappingRunsNicerThanTracking) {
  test::TempDir tmp;
  synth::SynthOptions synth_options;
  synth_options.frames = 3;
  synth_options.width = 320;
  synth_options.height = 240;
  synth_options.people = 0;
  synth::write_sequence(synth_options, tmp / "seq");
  const int own = getpriority(PRIO_PROCESS, 0);
  EXPECT_EQ(mapper_nice(tmp / "seq", 7), std::min(19, own + 7));
  EXPECT_EQ(mapper_nice(tmp / "seq", 0), own);
  EXPECT_EQ(nice_of_thread("cs-mapper"), -100);  // joined by shutdown
}
