// End-to-end monocular SLAM (`run --sensor mono`) on an RGB-D sequence from the synthetic generator, run
// from its colour images only, against the exact ground truth with Sim3 alignment.
#include <gtest/gtest.h>

#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/run/run_sequence.h"
#include "test_support.h"

using namespace crowdslam;

TEST(RunMonocular, SweepWithPeopleInitialisesEarlyAndTracksWithSim3AccuracyUnderOneCentimetre) {
  test::TempDir tmp;
  // The sweep translates from the first frame on (the default loop does too, but needs 300 frames for a
  // realistic speed); three people walk through the room and are filtered with their exact boxes.
  synth::SynthOptions synth_options;
  synth_options.frames = 60;
  synth_options.trajectory = synth::TrajectoryKind::kSweep;
  synth_options.people = 3;
  synth_options.seed = 1;
  const auto dataset = tmp / "sweep";
  synth::write_sequence(synth_options, dataset);

  run::RunOptions options;
  options.dataset = dataset.string();
  options.out_dir = (tmp / "out").string();
  options.sensor = io::SensorKind::kMonocular;
  options.sequential = true;
  options.progress = false;
  options.detections_file = (dataset / "people_gt.txt").string();
  options.vocabulary = "none";
  const auto summary = run::run_sequence(options);

  EXPECT_EQ(summary.json["sensor"], "monocular");
  ASSERT_TRUE(summary.init_frame.has_value());
  EXPECT_LE(*summary.init_frame, 30u);
  EXPECT_EQ(summary.json["summary"]["map_resets"], 0);
  // Every frame from the initialisation on is tracked, and so are the initialisation's reference frame
  // (its pose is the first keyframe's) and the earlier frames the new map localised (reported not
  // initialised at the time, marked localized_after_init).
  EXPECT_GE(summary.frames_localized_before_init, 1u);
  EXPECT_EQ(summary.tracked, summary.frames - *summary.init_frame + summary.frames_localized_before_init);
  size_t marked = 0;
  for (const auto& f : summary.json["frames"]) marked += f["localized_after_init"].get<bool>() ? 1 : 0;
  EXPECT_EQ(marked, summary.frames_localized_before_init);
  for (const auto& f : summary.json["frames"]) {
    EXPECT_EQ(f["state"], f["index"].get<size_t>() < *summary.init_frame ? "not_initialized" : "ok");
  }
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_EQ(summary.json["accuracy"]["alignment"], "sim3");
  EXPECT_LT(*summary.ate_rmse_m, 0.01);  // measured ~2.5 mm; the target is 2 cm
  // The map's unit is the first keyframe's median depth (about 2 m in this room), not a metre.
  const double scale = summary.json["accuracy"]["sim3_scale"].get<double>();
  EXPECT_GT(scale, 1.2);
  EXPECT_LT(scale, 4.0);
}
