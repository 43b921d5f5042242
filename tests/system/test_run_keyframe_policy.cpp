// End-to-end: the RGB-D / stereo keyframe policy's reference ratio (Tracking.keyframe_reference_ratio). A
// keyframe is due when the frame tracks fewer than that share of its reference keyframe's points; ORB-SLAM2
// uses 0.75 for RGB-D, crowdslam 0.9 (more keyframes measured better in crowds, fewer cost less CPU:
// docs/PROFILE.md). Sequential runs, where the mapper is always idle when tracking asks, so the ratio alone
// decides.
#include <gtest/gtest.h>

#include <iostream>
#include <nlohmann/json.hpp>

#include "crowdslam/run/run_sequence.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "run_test_options.h"
#include "test_support.h"

using namespace crowdslam;

namespace {

run::RunSummary run_with_ratio(const std::filesystem::path& dataset, const std::filesystem::path& out,
                               const std::string& ratio) {
  const auto settings = out.parent_path() / (out.filename().string() + ".yaml");
  test::write_text(settings,
                   test::read_text(dataset / "settings.yaml") + "\nTracking.keyframe_reference_ratio: " + ratio + "\n");
  run::RunOptions o = test::sequential_run_options(dataset, out);  // the empty room: no people filter
  o.settings_path = settings.string();
  return run::run_sequence(o);
}

}  // namespace

TEST(RunKeyframePolicy, ALowerReferenceRatioMakesFewerKeyframesAndKeepsTheRoomAccurate) {
  test::TempDir tmp;
  synth::SynthOptions options;
  options.frames = 150;
  options.seed = 5;
  const auto dataset = tmp / "room";
  synth::write_sequence(options, dataset);

  const auto many = run_with_ratio(dataset, tmp / "many", "0.9");
  const auto few = run_with_ratio(dataset, tmp / "few", "0.75");
  const auto made = [](const run::RunSummary& r) { return r.json["local_mapping"]["keyframes_processed"].get<int>(); };
  for (const auto* run : {&many, &few}) {
    EXPECT_EQ(run->json["summary"]["tracked_percent"].get<double>(), 100.0);
    EXPECT_EQ(run->json["summary"]["map_resets"].get<int>(), 0);
    ASSERT_TRUE(run->ate_rmse_m.has_value());
    EXPECT_LT(*run->ate_rmse_m, 0.01);
  }
  // Measured: 62 keyframes at 0.9, 42 at 0.75, 71 at 1.
  EXPECT_LT(made(few), made(many)) << "0.75: " << made(few) << ", 0.9: " << made(many);
  // A ratio of 1 asks for a keyframe whenever a single point is lost.
  const auto every = run_with_ratio(dataset, tmp / "every", "1");
  EXPECT_GT(made(every), made(many)) << "1: " << made(every) << ", 0.9: " << made(many);
  std::cout << "keyframes made: 0.75 " << made(few) << ", 0.9 " << made(many) << ", 1 " << made(every) << "\n";
}
