// End-to-end: a stereo camera in the synthetic passing crowd of 8 (people cut out of MOT, the default
// detector). Two people close to the camera leave a strip of background between them that the map never
// saw; with the rest of the view covered, the frames there were bridged one after another (12 of 300).
// With depth, mapping goes on from the bridged pose where the frame's keypoints outside the boxes see
// no map points (TrackerOptions::bridge_resume_min_keypoints): the frames after it are tracked again.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "crowdslam/synth/sprites.h"
#include "test_support.h"

namespace fs = std::filesystem;
using crowdslam::test::run_cli;

namespace {
// Why the crowd cannot be rendered with people a detector sees, or run with the default detector ("" = it
// can): the shared models and the person sprites the setup cuts out of the MOT sequences.
std::string missing_inputs() {
  if (!fs::exists(crowdslam::test::shared_dir() / "models" / "yolo-fastest-1.1")) return "shared detector models missing";
  if (!fs::exists(crowdslam::synth::default_sprite_dir() / "sprites.json")) {
    return "person sprites missing (scripts/build_people_sprites.sh)";
  }
  return "";
}

// `synth --frames 300 --seed SEED --people N --crowd PROFILE [extra]` into `seq`.
crowdslam::test::CliResult synth_crowd(const fs::path& seq, const std::string& profile, const std::string& people,
                                       const std::vector<std::string>& extra = {}, const std::string& seed = "5") {
  std::vector<std::string> args{"-q",     "synth",    "--out", seq.string(), "--frames", "300", "--seed", seed,
                                "--people", people, "--crowd", profile};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_cli(args);
}

// A sequential run of `seq` into `out` (`--allow-untracked`, and `extra`).
crowdslam::test::CliResult run_sequential(const fs::path& seq, const fs::path& out,
                                          const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--sequential",
                                "--allow-untracked"};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_cli(args);
}

// run_sequential's run.json; null (and a test failure) when the run failed.
nlohmann::json run_json(const fs::path& seq, const fs::path& out, const std::vector<std::string>& extra = {}) {
  const auto run = run_sequential(seq, out, extra);
  if (run.exit_code != 0) {
    ADD_FAILURE() << "crowdslam run exited with " << run.exit_code << ": " << run.err;
    return nullptr;
  }
  return nlohmann::json::parse(crowdslam::test::read_text(out / "run.json"));
}

// `seq`'s settings with `extra` lines after them, written to `path`: the --settings arguments.
std::vector<std::string> settings_with(const fs::path& seq, const fs::path& path, const std::string& extra) {
  crowdslam::test::write_text(path, crowdslam::test::read_text(seq / "settings.yaml") + "\n" + extra);
  return {"--settings", path.string()};
}
}  // namespace


TEST(RunCrowdBridge, StereoCrowdMapsTheBackgroundBetweenPeopleFromTheBridgedPoseAndKeepsOneMap) {
  if (const std::string why = missing_inputs(); !why.empty()) GTEST_SKIP() << why;
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "crowd";
  const auto synth = synth_crowd(seq, "passing", "8", {"--stereo"});
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  // Masks of the raw boxes (Crowd-SLAM's; stereo's default is the NMS boxes), which cover the background
  // between people: frames then keep too few keypoints to track, and the bridge carries them. Box
  // keypoints off (by default they take back frames the map holds the background of): the bridge is what
  // this test measures.
  const auto doc = run_json(
      seq, tmp / "run",
      settings_with(seq, tmp / "raw_boxes.yaml", "Detector.filter_before_nms: 1\nPeopleFilter.static_in_boxes: \"monocular\"\n"));
  ASSERT_FALSE(doc.is_null());
  const auto& summary = doc["summary"];
  EXPECT_EQ(summary["map_resets"].get<int>(), 0);
  // Frames that made a keyframe from the bridged pose while people still covered half the keypoints or
  // more: reported bridged (never counted as tracked), and tracking goes on from them.
  int resumed_under_people = 0;
  int tracked_after = 0;
  const auto& frames = doc["frames"];
  for (size_t i = 0; i + 1 < frames.size(); ++i) {
    const auto& f = frames[i];
    if (f["state"] != "bridged" || !f["keyframe"].get<bool>()) continue;
    const double removed = 1.0 - f["keypoints"].get<double>() / f["keypoints_before_filter"].get<double>();
    if (removed < 0.5) continue;
    ++resumed_under_people;
    EXPECT_EQ(f["tracked_points"].get<int>(), 0) << "frame " << f["index"];
    if (frames[i + 1]["state"] == "ok") ++tracked_after;
  }
  std::printf("tracked %.1f %%, %d bridged, %d resumed while people covered the view (%d tracked right after), "
              "ATE %.4f m\n",
              summary["tracked_percent"].get<double>(), summary["bridged_frames"].get<int>(), resumed_under_people,
              tracked_after, summary["ate_rmse_m"].get<double>());
  EXPECT_GE(resumed_under_people, 1);
  EXPECT_GE(tracked_after, 1);
  // Before: 96.0 % tracked (12 frames bridged), ATE 0.026 m; the empty room: 0.004 m.
  EXPECT_GE(summary["tracked_percent"].get<double>(), 97.0);
  EXPECT_LT(summary["ate_rmse_m"].get<double>(), 0.03);
}

// Stereo, people crossing close to the camera (`near` 8, seed 7, the default detector): a person half a
// metre away hides most of the view for a few frames while the camera turns. When it steps aside, the
// frame's view is new ground beside the person and the map's points lie behind it; the frame failed to
// track, and with the map "in view" it was lost, relocalisation found nothing and a new map started in
// every run (84 % tracked). A bridge this short (TrackerOptions::bridge_resume_recent_s) has barely
// drifted: mapping goes on from its pose, and the run keeps one map.
TEST(RunCrowdBridge, StereoMapsOnAfterAShortBridgeWhereTheViewClearsOntoNewGround) {
  if (const std::string why = missing_inputs(); !why.empty()) GTEST_SKIP() << why;
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "near";
  const auto synth = synth_crowd(seq, "near", "8", {"--stereo"}, "7");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  const auto doc = run_json(seq, tmp / "run");
  ASSERT_FALSE(doc.is_null());
  const auto& summary = doc["summary"];
  // Keyframes made from a bridged pose once the filter took less than half the keypoints (the view clear).
  int resumed_in_clear_view = 0;
  for (const auto& f : doc["frames"]) {
    if (f["state"] != "bridged" || !f["keyframe"].get<bool>()) continue;
    EXPECT_EQ(f["tracked_points"].get<int>(), 0) << "frame " << f["index"];
    if (f["keypoints"].get<double>() > 0.5 * f["keypoints_before_filter"].get<double>()) ++resumed_in_clear_view;
  }
  std::printf("tracked %.1f %%, %d bridged, %d mapped on from a short bridge with the view clear, %d new maps, "
              "ATE %.4f m\n",
              summary["tracked_percent"].get<double>(), summary["bridged_frames"].get<int>(), resumed_in_clear_view,
              summary["map_resets"].get<int>(), summary["ate_rmse_m"].get<double>());
  EXPECT_EQ(summary["map_resets"].get<int>(), 0);
  EXPECT_GE(resumed_in_clear_view, 1);
  EXPECT_GE(summary["tracked_percent"].get<double>(), 95.0);
  // One map over the whole run, drifting by centimetres where people cover most of the view (the empty
  // room: 0.003 m).
  EXPECT_LT(summary["ate_rmse_m"].get<double>(), 0.1);
}

// Stereo blackout with YOLOX: when the crowd steps away, the first frames show the room again but stereo
// matches none of it yet (blurred, half covered), so the bridge's end mapped on from a keyframe without
// points, the frames after it were lost, and a new map started in every run (73 % tracked). A frame after a
// bridge with fewer than 50 keypoints with depth off the people (TrackerOptions::
// bridge_resume_min_depth_keypoints) is bridged on instead; the next one, with depth, maps on.
TEST(RunCrowdBridge, StereoBlackoutBridgesOnUntilTheFrameHasDepthToMapOn) {
  if (const std::string why = missing_inputs(); !why.empty()) GTEST_SKIP() << why;
  if (!fs::exists(crowdslam::test::shared_dir() / "models" / "yolox-nano")) GTEST_SKIP() << "YOLOX model missing";
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "blackout";
  const auto synth = synth_crowd(seq, "blackout", "8", {"--stereo"});
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  const int last_covered = nlohmann::json::parse(crowdslam::test::read_text(seq / "synth.json"))["blackout_frames"][1];
  const auto doc = run_json(seq, tmp / "run", {"--detector", "yolox"});
  ASSERT_FALSE(doc.is_null());
  // After the blackout: bridged frames whose view has cleared (the filter took less than half the
  // keypoints) but that stereo found (almost) no depth in; never keyframes.
  int bridged_without_depth = 0;
  for (const auto& f : doc["frames"]) {
    if (f["index"].get<int>() <= last_covered || f["state"] != "bridged") continue;
    if (f["keypoints"].get<double>() <= 0.5 * f["keypoints_before_filter"].get<double>()) continue;
    if (f["stereo_matches"].get<int>() >= 50) continue;
    ++bridged_without_depth;
    EXPECT_FALSE(f["keyframe"].get<bool>()) << "frame " << f["index"];
  }
  const auto& report = doc["accuracy"]["bridged"];
  std::printf("%d frames bridged on for lack of depth after the blackout, tracked %.1f %%, %d new maps, "
              "after/before %.2f\n",
              bridged_without_depth, doc["summary"]["tracked_percent"].get<double>(),
              doc["summary"]["map_resets"].get<int>(), report["after_over_before_max"].get<double>());
  EXPECT_GE(bridged_without_depth, 1);
  EXPECT_EQ(doc["summary"]["map_resets"].get<int>(), 0);
  EXPECT_GE(doc["summary"]["tracked_percent"].get<double>(), 80.0);
  // When the view clears, the pose is back within twice the error it had before the crowd covered it.
  EXPECT_LE(report["after_over_before_max"].get<double>(), 2.0);
}

// RGB-D blackout with the default detector: people fill the view from half a metre, cut by the image's
// edges, and the detector misses them in most of those frames, so the people filter takes nothing and
// the frames were lost, and a second later a new map started. With depth, a frame whose keypoints are
// mostly nearer than half the scene's depth before is hidden too (TrackerOptions::bridge_near_depth_ratio):
// bridged, never mapped from, and the run keeps one map.
TEST(RunCrowdBridge, RgbdBlackoutTheDetectorMissesIsBridgedByDepthInOneMap) {
  if (const std::string why = missing_inputs(); !why.empty()) GTEST_SKIP() << why;
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "blackout";
  const auto synth = synth_crowd(seq, "blackout", "8");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  const auto planned = nlohmann::json::parse(crowdslam::test::read_text(seq / "synth.json"))["blackout_frames"];
  const int first = planned[0].get<int>();
  const int last = planned[1].get<int>();
  const auto doc = run_json(seq, tmp / "run");
  ASSERT_FALSE(doc.is_null());
  EXPECT_EQ(doc["summary"]["map_resets"].get<int>(), 0);
  int covered = 0;
  int covered_bridged = 0;
  int undetected_bridged = 0;  // bridged although the filter took less than half the keypoints
  double last_bridged_s = -1e9;
  for (const auto& f : doc["frames"]) {
    const int index = f["index"].get<int>();
    // Frames moments after a bridge are left to it, not taken back with box keypoints matched to points
    // mapped on from the bridged pose (TrackerOptions::box_rescue_after_bridge_s).
    if (f["state"] == "bridged") last_bridged_s = f["timestamp"].get<double>();
    if (f["method"] == "motion+boxes" || f["method"] == "relocalization+boxes") {
      EXPECT_GE(f["timestamp"].get<double>() - last_bridged_s, 1.0) << "frame " << index;
    }
    if (index < first || index > last) continue;
    ++covered;
    if (f["state"] != "bridged") continue;
    ++covered_bridged;
    if (f["keypoints"].get<double>() > 0.5 * f["keypoints_before_filter"].get<double>()) ++undetected_bridged;
  }
  const auto& report = doc["accuracy"]["bridged"];
  std::printf("%d of %d covered frames bridged (%d the filter took less than half of), tracked %.1f %%, "
              "after/before %.2f\n",
              covered_bridged, covered, undetected_bridged, doc["summary"]["tracked_percent"].get<double>(),
              report["after_over_before_max"].get<double>());
  EXPECT_GE(covered_bridged, covered * 9 / 10);
  EXPECT_GE(undetected_bridged, 1);
  // When the view clears, the pose is back within twice the error it had before the crowd covered it.
  EXPECT_LE(report["after_over_before_max"].get<double>(), 2.0);
}

// RGB-D, the passing crowd of 16 with the default detector: in frames 140 and 257-266 people cover 78-100 %
// of the image by their boxes (the detector also fires at 0.2-0.5 on a wall of photographs), and the
// filter leaves 10-150 keypoints, too few to track, while 40 % of the view is background the map holds.
// Those frames were bridged (7 of 300). With depth the default box keypoints ("auto") take such a frame
// back: its keypoints in boxes are matched to the map's trusted points from the motion model's pose, and
// the pose needs 50 inliers (388 in frame 258) and must lie near the motion model's; nothing of the boxes
// is mapped and the frame makes no keyframe.
TEST(RunCrowdBridge, RgbdFramesTheFilterLeavesTooLittleAreTakenBackByTheMapsPointsInTheBoxes) {
  if (const std::string why = missing_inputs(); !why.empty()) GTEST_SKIP() << why;
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "crowd";
  const auto synth = synth_crowd(seq, "passing", "16");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  const auto doc = run_json(seq, tmp / "run");
  ASSERT_FALSE(doc.is_null());
  const auto& summary = doc["summary"];
  EXPECT_EQ(summary["map_resets"].get<int>(), 0);
  EXPECT_EQ(summary["bridged_frames"].get<int>(), 0);
  // The first frame starts the map: the filter took 51 % of its keypoints and left 490 with depth, fewer
  // than the 500 of an empty view but as many as the frame had before the filter in proportion
  // (TrackerOptions::min_init_static_features). Frames 0 and 1 waited before.
  EXPECT_EQ(doc["frames"][0]["method"], "init");
  int rescued = 0;
  for (const auto& f : doc["frames"]) {
    EXPECT_EQ(f["state"], "ok") << "frame " << f["index"];
    EXPECT_EQ(f["static_boxes"].get<int>(), 0) << "frame " << f["index"];
    if (f["method"] == "motion+boxes") ++rescued;
  }
  EXPECT_GE(rescued, 3);
  EXPECT_LT(summary["ate_rmse_m"].get<double>(), 0.015);  // 0.0114 m (0.0091 m with the bridged frames)

  // Without box keypoints ("monocular": monocular runs only) those frames are bridged.
  const auto without_doc =
      run_json(seq, tmp / "without", settings_with(seq, tmp / "without.yaml", "PeopleFilter.static_in_boxes: \"monocular\"\n"));
  ASSERT_FALSE(without_doc.is_null());
  EXPECT_GE(without_doc["summary"]["bridged_frames"].get<int>(), rescued);
}

// Monocular, a standing crowd of 30 (the generator's boxes): a group stands in front of the camera for 3 s
// while it turns to walls the map never saw, leaving a few hundred background keypoints between people.
// The frames were bridged until the group parted and the camera was lost (87 frames bridged, 71 %
// tracked). Re-anchoring now starts on such a bridged frame (TrackerOptions::bridge_resume_min_keypoints
// off the people, few map points where the bridge puts it): the camera is tracked again in the same map
// while people still cover most of the view, and the bridged frames it localises become tracked frames
// (in CameraTrajectory.txt, no longer in BridgedTrajectory.txt).
TEST(RunCrowdBridge, MonocularReanchorsWhileBridgedOntoAViewTheMapNeverSaw) {
  if (const std::string why = missing_inputs(); !why.empty()) GTEST_SKIP() << why;
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "standing";
  const auto synth = synth_crowd(seq, "standing", "30");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  const auto out = tmp / "run";
  const auto doc = run_json(seq, out, {"--detections", (seq / "people_gt.txt").string(), "--sensor", "mono"});
  ASSERT_FALSE(doc.is_null());
  const auto& summary = doc["summary"];
  EXPECT_EQ(summary["map_resets"].get<int>(), 0);
  int reanchored_in_bridge = 0;
  const auto& frames = doc["frames"];
  for (size_t i = 1; i < frames.size(); ++i) {
    if (frames[i]["method"] == "reanchor" && frames[i - 1]["state"] == "bridged") ++reanchored_in_bridge;
  }
  std::printf("tracked %.1f %%, %d bridged, %d re-anchorings during a bridge, %d frames localised after them\n",
              summary["tracked_percent"].get<double>(), summary["bridged_frames"].get<int>(), reanchored_in_bridge,
              summary["frames_localized_after_reanchor"].get<int>());
  EXPECT_GE(reanchored_in_bridge, 1);
  EXPECT_GE(summary["tracked_percent"].get<double>(), 90.0);
  EXPECT_LT(summary["bridged_frames"].get<int>(), 50);
  // A frame is either tracked or bridged, never both.
  const auto stamps = [](const fs::path& file) {
    std::set<std::string> out;
    std::istringstream in(crowdslam::test::read_text(file));
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line[0] != '#') out.insert(line.substr(0, line.find(' ')));
    }
    return out;
  };
  const auto tracked = stamps(out / "CameraTrajectory.txt");
  const auto bridged = stamps(out / "BridgedTrajectory.txt");
  EXPECT_EQ(static_cast<int>(tracked.size()), summary["tracked_frames"].get<int>());
  for (const auto& t : bridged) EXPECT_EQ(tracked.count(t), 0u) << t;
  EXPECT_GE(bridged.size(), 1u);
}
