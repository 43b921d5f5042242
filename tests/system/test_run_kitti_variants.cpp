// kitti07_head played another way (issue 11: "other real sequences and variants will be used"): at a
// third and a quarter of its rate (3.3 Hz: 6-10 degrees of turn and up to 1.5 m between frames; 2.5 Hz:
// up to 12 degrees) and from frame 30, in the middle of the left turn. They broke in sessions 16-17: at a
// third of the rate the threaded run lost track in the turn for good (32 % tracked) because tracking went
// on with ever fewer points without asking for a keyframe (its reference keyframe was as weak); at a
// quarter it lost the turn because due keyframes were skipped while the mapper was busy; from frame 30
// the six frames before the two-view initialisation stayed unlocalised (91 % tracked).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "crowdslam/io/dataset.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/run/run_sequence.h"
#include "crowdslam/system/system.h"
#include "test_support.h"

using namespace crowdslam;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> read_lines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

// A KITTI-layout variant of `src`, as scripts/make_variant.py makes it: frames start, start + stride, ...
// with their times and ground-truth poses; images linked, not copied. Returns the number of frames.
size_t write_kitti_variant(const fs::path& src, const fs::path& out, size_t start, size_t stride) {
  const auto times = read_lines(src / "times.txt");
  const auto poses = read_lines(src / "poses.txt");
  fs::create_directories(out / "image_0");
  fs::copy_file(src / "calib.txt", out / "calib.txt");
  std::ofstream times_out(out / "times.txt");
  std::ofstream poses_out(out / "poses.txt");
  size_t n = 0;
  for (size_t i = start; i < times.size() && i < poses.size(); i += stride, ++n) {
    char from[32], to[32];
    std::snprintf(from, sizeof from, "%06zu.png", i);
    std::snprintf(to, sizeof to, "%06zu.png", n);
    fs::create_symlink(fs::absolute(src / "image_0" / from), out / "image_0" / to);
    times_out << times[i] << '\n';
    poses_out << poses[i] << '\n';
  }
  return n;
}

run::RunOptions kitti_mono(const fs::path& dataset, const fs::path& out) {
  run::RunOptions options;
  options.dataset = dataset.string();
  options.settings_path = (test::source_dir() / "config" / "KITTI04-12.yaml").string();
  options.out_dir = out.string();
  options.sensor = io::SensorKind::kMonocular;
  options.progress = false;
  options.people_filter = false;
  return options;
}

// Runs every `stride`-th frame of kitti07_head threaded (the default) and checks one map, no reset, at
// least `min_tracked` frames tracked and an ATE under 0.6 m over the 54 m.
void expect_tracked_through_the_turn(size_t stride, size_t expected_frames, size_t min_tracked) {
  test::TempDir tmp;
  const auto variant = tmp / ("stride" + std::to_string(stride));
  ASSERT_EQ(write_kitti_variant(test::shared_data("kitti07_head"), variant, 0, stride), expected_frames);
  const auto summary = run::run_sequence(kitti_mono(variant, tmp / "out"));
  EXPECT_EQ(summary.json["summary"]["map_resets"], 0);
  EXPECT_EQ(summary.segments.size(), 1u);
  EXPECT_GE(summary.tracked, min_tracked);
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.6);
  std::printf("[ measured ] kitti07_head one frame in %zu, threaded: %zu/%zu tracked, ATE %.3f m, %d keyframes\n",
              stride, summary.tracked, summary.frames, *summary.ate_rmse_m,
              summary.json["summary"]["keyframes"].get<int>());
}

}  // namespace

// Weak tracking asks for a keyframe and waits for the mapper, so the turn at 3.3 Hz is tracked through
// with one map (measured 0.32-0.33 m over every frame).
TEST(RunKittiVariants, AThirdOfTheRateKeepsTrackThroughTheTurn) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  expect_tracked_through_the_turn(3, 34u, 33u);  // 97 % of 34
}

// Every 4th frame (2.5 Hz: up to 12 degrees of turn between frames). A threaded run that skipped a due
// keyframe because the mapper was busy lost the turn at frame 8 (32-36 % tracked, a new map that never
// initialised) while `--sequential` tracked it all: the next frame, two views of the turn further on, had
// no map points. The unpaced run waits for each due keyframe (measured 0.35-0.37 m without the ground).
TEST(RunKittiVariants, AQuarterOfTheRateKeepsTrackThroughTheTurn) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  expect_tracked_through_the_turn(4, 25u, 25u);
}

// The same with a mapper slowed by 80 ms per keyframe (SystemOptions::mapper_delay_ms): a frame that
// tracks weakly makes a keyframe, and the next frame waits until the mapper has mapped it, so the slow
// mapper costs time (recorded as waits), not the track.
TEST(RunKittiVariants, AThirdOfTheRateWithASlowMapperWaitsInsteadOfLosingTrack) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  test::TempDir tmp;
  ASSERT_EQ(write_kitti_variant(test::shared_data("kitti07_head"), tmp / "stride3", 0, 3), 34u);
  auto dataset = io::open_dataset((tmp / "stride3").string());
  const auto settings = io::load_settings((test::source_dir() / "config" / "KITTI04-12.yaml").string(),
                                          io::SensorKind::kMonocular);
  system::SystemOptions options;
  options.sensor = io::SensorKind::kMonocular;
  options.people_filter = false;
  options.mapper_delay_ms = 80.0;
  system::System slam(settings, options);
  size_t frames = 0;
  int frames_waited = 0;
  while (auto frame = dataset->next()) {
    const auto report = slam.track(frame->images, frame->info.timestamp_s);
    ++frames;
    if (report.waited_for_mapping_ms > 0) ++frames_waited;
  }
  slam.shutdown();
  std::printf(
      "[ measured ] every 3rd frame, mapper +80 ms: %zu/%zu tracked, %d frames waited, %zu keyframes\n",
      slam.tracked_frames(), frames, frames_waited, slam.keyframe_trajectory().size());
  EXPECT_EQ(slam.map_resets(), 0);
  EXPECT_GE(slam.tracked_frames(), 33u);
  EXPECT_GT(frames_waited, 0);
}

// An unpaced run waits for every due keyframe (SystemOptions::replay_waits_for_mapping), so a slow mapper
// costs time, not keyframes; a paced run (a live camera, `--pace sensor`) waits only for urgent ones and
// makes fewer. kitti07_head as recorded, mapper slowed by 30 ms per keyframe.
TEST(RunKittiVariants, AnUnpacedRunWaitsForEveryDueKeyframe) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  const auto settings = io::load_settings((test::source_dir() / "config" / "KITTI04-12.yaml").string(),
                                          io::SensorKind::kMonocular);
  struct Outcome {
    size_t tracked = 0;
    size_t keyframes = 0;
    int frames_waited = 0;
  };
  const auto run = [&](bool wait_for_due) {
    auto dataset = io::open_dataset(test::shared_data("kitti07_head").string());
    system::SystemOptions options;
    options.sensor = io::SensorKind::kMonocular;
    options.people_filter = false;
    options.mapper_delay_ms = 30.0;
    options.replay_waits_for_mapping = wait_for_due;
    system::System slam(settings, options);
    Outcome o;
    while (auto frame = dataset->next()) {
      const auto report = slam.track(frame->images, frame->info.timestamp_s);
      if (report.new_keyframe) ++o.keyframes;
      if (report.waited_for_mapping_ms > 0) ++o.frames_waited;
    }
    slam.shutdown();
    o.tracked = slam.tracked_frames();
    return o;
  };
  const Outcome waiting = run(true);
  const Outcome urgent_only = run(false);
  std::printf(
      "[ measured ] kitti07_head, mapper +30 ms: waiting for due keyframes %zu tracked, %zu keyframes,"
      " %d frames waited; urgent ones only %zu tracked, %zu keyframes, %d waited\n",
      waiting.tracked, waiting.keyframes, waiting.frames_waited, urgent_only.tracked, urgent_only.keyframes,
      urgent_only.frames_waited);
  EXPECT_EQ(waiting.tracked, 100u);
  EXPECT_GT(waiting.frames_waited, urgent_only.frames_waited);
  EXPECT_GE(static_cast<double>(waiting.keyframes), 1.25 * static_cast<double>(urgent_only.keyframes));
}

// The unpaced default waits for local mapping as sequential mode would (every due keyframe, and the frame
// after a keyframe for its new points), so it makes about the keyframes of a `--sequential` run, with its
// accuracy. Threaded runs that did not wait made 38-41 keyframes against 82, at 0.346 m over keyframes against 0.276 m.
TEST(RunKittiVariants, AnUnpacedRunMakesTheKeyframesOfASequentialOne) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  test::TempDir tmp;
  auto options = kitti_mono(test::shared_data("kitti07_head"), tmp / "sequential");
  options.sequential = true;
  const auto sequential = run::run_sequence(options);
  const auto threaded = run::run_sequence(kitti_mono(test::shared_data("kitti07_head"), tmp / "threaded"));
  const auto keyframes = [](const run::RunSummary& s) {
    return s.json["summary"]["keyframes"].get<double>();
  };
  const auto keyframe_ate = [](const run::RunSummary& s) {
    return s.json["accuracy"]["ate_keyframes_rmse_m"].get<double>();
  };
  std::printf(
      "[ measured ] kitti07_head: sequential %.0f keyframes, ATE %.3f m over them; threaded %.0f, %.3f m\n",
      keyframes(sequential), keyframe_ate(sequential), keyframes(threaded), keyframe_ate(threaded));
  EXPECT_EQ(threaded.tracked, threaded.frames);
  EXPECT_GE(keyframes(threaded), 0.85 * keyframes(sequential));
  EXPECT_LT(keyframe_ate(threaded), 1.25 * keyframe_ate(sequential));
}

// From frame 30 the initializer needs 8 frames of the turn; the frames before its reference are taken
// backwards from it (the first step extrapolated from the two keyframes' motion), and those the two-view
// map cannot hold are tried again once the mapper has grown the map.
TEST(RunKittiVariants, ALaterStartLocalisesEveryFrameBeforeTheInitialisation) {
  CROWDSLAM_REQUIRE_SHARED("kitti07_head");
  test::TempDir tmp;
  const size_t frames = write_kitti_variant(test::shared_data("kitti07_head"), tmp / "from30", 30, 1);
  ASSERT_EQ(frames, 70u);
  auto options = kitti_mono(tmp / "from30", tmp / "out");
  options.sequential = true;
  const auto summary = run::run_sequence(options);
  ASSERT_TRUE(summary.init_frame.has_value());
  EXPECT_GE(*summary.init_frame, 4u);  // the turn: the first frames do not initialise
  EXPECT_EQ(summary.json["summary"]["map_resets"], 0);
  EXPECT_EQ(summary.frames_localized_before_init, *summary.init_frame);
  EXPECT_EQ(summary.tracked, summary.frames);
  const auto& json_frames = summary.json["frames"];
  for (size_t i = 0; i < *summary.init_frame; ++i) {
    EXPECT_TRUE(json_frames[i]["localized_after_init"].get<bool>()) << i;
  }
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.1);  // 40 m of straight road after the turn: measured 0.037 m
  std::printf("[ measured ] kitti07_head from frame 30: initialised at %zu, %zu/%zu tracked, ATE %.3f m\n",
              *summary.init_frame, summary.tracked, summary.frames, *summary.ate_rmse_m);
}
