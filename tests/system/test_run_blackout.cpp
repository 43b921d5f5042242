// End-to-end: a crowd that covers the whole view for 1.5 s (synth --crowd blackout) with the generator's
// exact person boxes. The frames without static evidence are bridged by the motion model: reported
// "bridged", never counted as tracked, written to BridgedTrajectory.txt only, and the run keeps one map.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "crowdslam/eval/ate.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/run/run_sequence.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/writer.h"
#include "test_support.h"

using namespace crowdslam;

namespace {
struct Blackout {
  std::filesystem::path dir;
  int first = -1;  // frames the generator planned the view to be covered (0-based)
  int last = -1;
};

Blackout make_blackout(const test::TempDir& tmp) {
  synth::SynthOptions options;
  options.frames = 240;
  options.people = 6;
  options.seed = 5;
  options.crowd = synth::CrowdProfile::kBlackout;  // box people (no sprite_dir): the boxes are exact
  Blackout b;
  b.dir = tmp / "blackout";
  synth::write_sequence(options, b.dir);
  const auto json = nlohmann::json::parse(test::read_text(b.dir / "synth.json"));
  b.first = json["blackout_frames"][0].get<int>();
  b.last = json["blackout_frames"][1].get<int>();
  return b;
}

run::RunSummary run_on(const Blackout& b, const std::filesystem::path& out, const std::string& extra = "",
                       std::optional<io::SensorKind> sensor = std::nullopt) {
  run::RunOptions o;
  o.sensor = sensor;
  o.dataset = b.dir.string();
  o.out_dir = out.string();
  o.sequential = true;
  o.progress = false;
  o.detections_file = (b.dir / "people_gt.txt").string();
  if (!extra.empty()) {
    const auto settings = out.parent_path() / (out.filename().string() + ".yaml");
    test::write_text(settings, test::read_text(b.dir / "settings.yaml") + extra);
    o.settings_path = settings.string();
  }
  return run::run_sequence(o);
}
}  // namespace

TEST(RunBlackout, BridgedFramesKeepOneMapAndAreNeverCountedAsTracked) {
  test::TempDir tmp;
  const Blackout b = make_blackout(tmp);
  ASSERT_GE(b.first, 0);
  ASSERT_GT(b.last, b.first + 20);
  const auto summary = run_on(b, tmp / "out");
  const auto& doc = summary.json;
  EXPECT_EQ(doc["summary"]["map_resets"].get<int>(), 0);
  EXPECT_EQ(doc["segments"].size(), 1u);

  // Per frame: bridged frames are marked, have no tracked points, and lie around the blackout.
  int bridged = 0, tracked = 0;
  std::set<double> bridged_stamps;
  for (const auto& f : doc["frames"]) {
    const std::string state = f["state"];
    if (state == "ok") ++tracked;
    if (state != "bridged") continue;
    ++bridged;
    bridged_stamps.insert(f["timestamp"].get<double>());
    EXPECT_EQ(f["method"], "bridged") << "frame " << f["index"];
    EXPECT_EQ(f["tracked_points"].get<int>(), 0) << "frame " << f["index"];
    const int index = f["index"].get<int>();
    EXPECT_GE(index, b.first - 15) << "bridged long before the crowd covered the view";
    EXPECT_LE(index, b.last + 15) << "bridged long after the view cleared";
  }
  // Most of the covered frames are bridged (a few at its edges may still track or be lost).
  EXPECT_GE(bridged, (b.last - b.first + 1) * 2 / 3);
  EXPECT_EQ(doc["summary"]["bridged_frames"].get<int>(), bridged);
  EXPECT_EQ(summary.bridged, static_cast<size_t>(bridged));
  EXPECT_EQ(static_cast<int>(summary.tracked), tracked);
  EXPECT_LE(summary.tracked + summary.bridged, summary.frames);

  // CameraTrajectory.txt holds the tracked frames only; BridgedTrajectory.txt the bridged ones.
  const auto camera = io::read_tum_trajectory((tmp / "out" / "CameraTrajectory.txt").string());
  const auto bridged_poses = io::read_tum_trajectory((tmp / "out" / "BridgedTrajectory.txt").string());
  EXPECT_EQ(camera.size(), summary.tracked);
  ASSERT_EQ(bridged_poses.size(), static_cast<size_t>(bridged));
  for (const auto& pose : camera) {
    for (const double s : bridged_stamps) EXPECT_GT(std::abs(pose.timestamp_s - s), 1e-4);
  }
  // The drift of the bridge is reported against the ground truth.
  const auto& report = doc["accuracy"]["bridged"];
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report["frames"].get<int>(), bridged);
  EXPECT_GE(report["bridges"].get<int>(), 1);
  EXPECT_GT(report["error_max_m"].get<double>(), 0.0);
  EXPECT_LT(report["error_max_m"].get<double>(), 1.0);  // a 1.5 s bridge at walking speed

  // Without the bridge the covered frames are lost, and after a second a new map starts.
  const auto without = run_on(b, tmp / "without", "\nTracking.bridge_max_s: 0\n");
  EXPECT_EQ(without.bridged, 0u);
  EXPECT_GE(without.json["summary"]["map_resets"].get<int>(), 1);
}

// Monocular: when the view clears onto what the map does not hold, the camera is lost. Re-anchoring
// (Tracking.reanchor_max_s) makes a two-view map there and places it in the same map by the motion before
// the loss, scaled by it: one map, and the frames after it keep the scale of the frames before.
TEST(RunBlackout, MonocularReanchorsIntoTheSameMapWithTheScaleOfBefore) {
  test::TempDir tmp;
  const Blackout b = make_blackout(tmp);
  const auto summary = run_on(b, tmp / "mono", "", io::SensorKind::kMonocular);
  const auto& doc = summary.json;
  EXPECT_EQ(doc["summary"]["map_resets"].get<int>(), 0);
  EXPECT_EQ(doc["segments"].size(), 1u);
  ASSERT_GE(doc["summary"]["reanchors"].get<int>(), 1);
  double reanchor_s = -1;
  int lost_before = 0;
  for (const auto& f : doc["frames"]) {
    if (f["method"] == "reanchor") {
      reanchor_s = f["timestamp"].get<double>();
      break;
    }
    if (f["state"] == "lost") ++lost_before;
  }
  ASSERT_GT(reanchor_s, 0);
  EXPECT_GE(lost_before, 1);  // re-anchoring follows a loss; frames before it are reported lost
  // Lost frames the re-anchored map localised afterwards (and bridged frames before them, reached across
  // the frames that fail): reported lost or bridged, tracked in the trajectory.
  std::set<long> recovered_ms;  // their time stamps, in ms
  size_t ok_frames = 0;
  size_t localized = 0;
  for (const auto& f : doc["frames"]) {
    if (f["state"] == "ok") ++ok_frames;
    if (f["localized_after_init"].get<bool>()) ++localized;
    if (!f["localized_after_reanchor"].get<bool>()) continue;
    EXPECT_TRUE(f["state"] == "lost" || f["state"] == "bridged") << f["state"];
    EXPECT_LT(f["timestamp"].get<double>(), reanchor_s);
    recovered_ms.insert(std::lround(f["timestamp"].get<double>() * 1000));
  }
  EXPECT_EQ(recovered_ms.size(), doc["summary"]["frames_localized_after_reanchor"].get<size_t>());
  // A frame is tracked or bridged or neither, never both (a bridged frame localised later is tracked).
  EXPECT_LE(doc["summary"]["tracked_frames"].get<size_t>() + doc["summary"]["bridged_frames"].get<size_t>(),
            doc["summary"]["frames"].get<size_t>());
  EXPECT_GE(recovered_ms.size(), 1u);  // at least the re-anchoring's reference frame, now a keyframe
  EXPECT_EQ(doc["summary"]["tracked_frames"].get<size_t>(), ok_frames + localized + recovered_ms.size());
  // Scale of the tracked poses before and after the re-anchoring, each aligned to the ground truth (Sim3).
  const auto camera = io::read_tum_trajectory((tmp / "mono" / "CameraTrajectory.txt").string());
  const auto truth = io::read_tum_trajectory((b.dir / "groundtruth.txt").string());
  io::Trajectory before, after, after_and_recovered;
  size_t recovered_in_trajectory = 0;
  for (const auto& pose : camera) {
    if (recovered_ms.count(std::lround(pose.timestamp_s * 1000))) {
      ++recovered_in_trajectory;
      after_and_recovered.push_back(pose);
      continue;
    }
    (pose.timestamp_s < reanchor_s ? before : after).push_back(pose);
    if (pose.timestamp_s >= reanchor_s) after_and_recovered.push_back(pose);
  }
  EXPECT_EQ(recovered_in_trajectory, recovered_ms.size());
  ASSERT_GE(before.size(), 30u);
  ASSERT_GE(after.size(), 30u);
  eval::AteOptions sim3;
  sim3.alignment = eval::Alignment::kSim3;
  const double scale_before = eval::evaluate_ate(truth, before, sim3).alignment.scale;
  const double scale_after = eval::evaluate_ate(truth, after, sim3).alignment.scale;
  std::printf("[ measured ] monocular blackout: re-anchored at %.2f s, scale before %.3f after %.3f, ATE %.4f m\n",
              reanchor_s, scale_before, scale_after, doc["summary"]["ate_rmse_m"].get<double>());
  EXPECT_NEAR(scale_after / scale_before, 1.0, 0.25);
  // The recovered frames agree with the re-anchored part they were localised in.
  std::sort(after_and_recovered.begin(), after_and_recovered.end(),
            [](const auto& a, const auto& c) { return a.timestamp_s < c.timestamp_s; });
  const double ate_after = eval::evaluate_ate(truth, after, sim3).translation_error_m.rmse;
  const double ate_with_recovered = eval::evaluate_ate(truth, after_and_recovered, sim3).translation_error_m.rmse;
  std::printf("[ measured ] %zu lost frames localised after the re-anchoring; ATE after %.4f m, with them %.4f m\n",
              recovered_ms.size(), ate_after, ate_with_recovered);
  EXPECT_LT(ate_with_recovered, 1.5 * ate_after + 0.005);

  // Without re-anchoring the camera stays lost, and a second later a new map starts.
  const auto without = run_on(b, tmp / "mono_without", "\nTracking.reanchor_max_s: 0\n", io::SensorKind::kMonocular);
  EXPECT_GE(without.json["summary"]["map_resets"].get<int>(), 1);
  EXPECT_EQ(without.json["summary"]["reanchors"].get<int>(), 0);
}

// Re-anchoring is counted from the loss, as the new-map clock: after a bridge, from when the view cleared.
// With a window shorter than the blackout's bridge, the window counted from the last pose before it would
// be over by then, and a new map would start.
TEST(RunBlackout, MonocularReanchoringIsCountedFromWhenTheViewCleared) {
  test::TempDir tmp;
  const Blackout b = make_blackout(tmp);
  const auto summary = run_on(b, tmp / "mono", "\nTracking.reanchor_max_s: 1.0\n", io::SensorKind::kMonocular);
  const auto& doc = summary.json;
  double last_bridged_s = -1;
  double last_pose_before_s = -1;
  double reanchor_s = -1;
  for (const auto& f : doc["frames"]) {
    const double t = f["timestamp"].get<double>();
    if (f["method"] == "reanchor") {
      reanchor_s = t;
      break;
    }
    if (f["state"] == "bridged") last_bridged_s = t;
    if (f["state"] == "ok" && last_bridged_s < 0) last_pose_before_s = t;
  }
  ASSERT_GT(last_bridged_s, 0) << "the blackout was not bridged";
  ASSERT_GT(reanchor_s, 0) << "not re-anchored";
  EXPECT_GT(reanchor_s - last_pose_before_s, 1.0);  // beyond the window, counted from the last pose
  EXPECT_LE(reanchor_s - last_bridged_s, 1.0 + 1e-6);
  EXPECT_EQ(doc["summary"]["map_resets"].get<int>(), 0);
  EXPECT_EQ(doc["segments"].size(), 1u);
}
