// Saved maps (issue 12): save -> load -> save is identical table by table; localisation in a loaded map
// creates nothing and reproduces the mapping run's poses; continuing a map grows it; people stay out.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "crowdslam/io/settings.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/schema.h"
#include "crowdslam/system/system.h"
#include "map_test_helpers.h"

using namespace crowdslam;

namespace {

system::SystemOptions rgbd_options() {
  system::SystemOptions o;
  o.sensor = io::SensorKind::kRgbd;
  o.sequential = true;
  o.people_filter = false;
  return o;
}

std::map<double, geometry::Vec3> positions(const std::filesystem::path& trajectory) {
  std::map<double, geometry::Vec3> out;
  for (const auto& pose : io::read_trajectory(trajectory.string())) out[pose.timestamp_s] = pose.world_from_cam.translation();
  return out;
}

}  // namespace

TEST(MapRoundTrip, SaveLoadSaveGivesIdenticalTables) {
  test::TempDir tmp;
  const auto room = test::make_room(tmp, 0);
  auto options = test::run_options(room, tmp / "mapping");
  options.save_map = (tmp / "a.db").string();
  const auto summary = run::run_sequence(options);
  ASSERT_EQ(summary.tracked, 120u);
  const auto& saved = summary.json["map"]["saved"];
  ASSERT_TRUE(saved.is_object());
  EXPECT_GT(saved["keyframes"].get<int>(), 3);
  EXPECT_GT(saved["bytes"].get<int>(), 10000);

  const auto settings = io::load_settings((room / "settings.yaml").string(), io::SensorKind::kRgbd);
  {
    system::System slam(settings, rgbd_options());
    const auto loaded = slam.load_map((tmp / "a.db").string(), false);
    EXPECT_EQ(loaded.keyframes.size(), slam.num_keyframes());
    EXPECT_EQ(slam.num_keyframes(), saved["keyframes"].get<size_t>());
    slam.save_map((tmp / "b.db").string(), mapdb::MapOrigin{"other", "never", "0", "completed"});
  }
  for (size_t t = 0; t < mapdb::kNumTables; ++t) {
    const auto a = test::dump_table(tmp / "a.db", mapdb::kTables[t]);
    const auto b = test::dump_table(tmp / "b.db", mapdb::kTables[t]);
    if (std::string(mapdb::kTables[t]) != "loop_edges") {  // no loop here
      EXPECT_FALSE(a.empty()) << mapdb::kTables[t];
    }
    EXPECT_EQ(a.size(), b.size()) << mapdb::kTables[t];
    EXPECT_TRUE(a == b) << "table " << mapdb::kTables[t] << " differs after save -> load -> save";
  }
  const auto header = mapdb::read_map_header(tmp / "a.db");
  EXPECT_EQ(header.identity.sensor, "rgbd");
  EXPECT_EQ(header.origin.dataset, room.string());
  EXPECT_EQ(header.origin.end_state, "completed");
}

TEST(MapRoundTrip, LocalizationCreatesNothingAndReproducesTheMappingRunsPoses) {
  test::TempDir tmp;
  const auto room = test::make_room(tmp, 0);
  auto mapping = test::run_options(room, tmp / "mapping");
  mapping.save_map = (tmp / "room.db").string();
  run::run_sequence(mapping);
  const auto info = mapdb::read_map_info(tmp / "room.db");

  auto localization = test::run_options(room, tmp / "localization");
  localization.load_map = (tmp / "room.db").string();
  localization.localization = true;
  const auto summary = run::run_sequence(localization);
  const auto& loaded = summary.json["map"]["loaded"];
  EXPECT_EQ(loaded["mode"], "localization");
  EXPECT_EQ(loaded["first_localized_frame"].get<int>(), 0);
  EXPECT_GE(summary.tracked, 118u);
  EXPECT_EQ(loaded["frames_localized"].get<size_t>(), summary.tracked);
  // Nothing created or removed.
  EXPECT_EQ(summary.json["summary"]["keyframes"].get<size_t>(), info.keyframes);
  EXPECT_EQ(summary.json["summary"]["map_points"].get<size_t>(), info.map_points);
  EXPECT_EQ(summary.json["local_mapping"]["keyframes_processed"].get<int>(), 0);
  // Same frame as the map: the poses agree with the mapping run's without any alignment.
  const auto live = positions(tmp / "mapping" / "CameraTrajectory.txt");
  const auto relocated = positions(tmp / "localization" / "CameraTrajectory.txt");
  double sum2 = 0;
  size_t n = 0;
  for (const auto& [t, p] : relocated) {
    const auto it = live.find(t);
    if (it == live.end()) continue;
    sum2 += (p - it->second).squaredNorm();
    ++n;
  }
  ASSERT_GT(n, 100u);
  EXPECT_LT(std::sqrt(sum2 / static_cast<double>(n)), 0.005);
  // And against the ground truth.
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.01);
}

TEST(MapRoundTrip, ContinueMappingGrowsTheMapAndStaysAccurate) {
  test::TempDir tmp;
  const auto room = test::make_room(tmp, 0);
  auto first = test::run_options(room, tmp / "first");
  first.max_frames = 60;
  first.save_map = (tmp / "half.db").string();
  run::run_sequence(first);
  const auto half = mapdb::read_map_info(tmp / "half.db");

  auto second = test::run_options(room, tmp / "second");
  second.load_map = (tmp / "half.db").string();
  second.save_map = (tmp / "full.db").string();
  const auto summary = run::run_sequence(second);
  EXPECT_EQ(summary.json["map"]["loaded"]["mode"], "continue_mapping");
  EXPECT_GE(summary.tracked, 118u);
  const auto full = mapdb::read_map_info(tmp / "full.db");
  EXPECT_GT(full.keyframes, half.keyframes);
  EXPECT_GT(full.map_points, half.map_points);
  ASSERT_TRUE(summary.ate_rmse_m.has_value());
  EXPECT_LT(*summary.ate_rmse_m, 0.01);
}

namespace {
struct PointsInBoxes {
  size_t frames_with_people = 0;
  size_t checked = 0;     // map points seen by keyframes of frames with people
  size_t inside = 0;      // ... at a keypoint inside a person box
  size_t inside_flat = 0;  // ... of those, in a frame where the run found a box flat
};

// Map points of the saved map at keypoints inside the ground-truth person boxes of their keyframes.
PointsInBoxes points_in_boxes(const std::filesystem::path& db, const std::filesystem::path& people_gt,
                              const nlohmann::json& run) {
  // Person boxes per frame index (MOT frame n = frame n - 1).
  std::map<uint64_t, std::vector<cv::Rect2f>> boxes;
  std::ifstream in(people_gt);
  std::string line;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::vector<double> v;
    std::string field;
    while (std::getline(ss, field, ',')) v.push_back(std::stod(field));
    boxes[static_cast<uint64_t>(v[0]) - 1].emplace_back(v[2], v[3], v[4], v[5]);
  }
  std::set<uint64_t> flat_frames;
  for (const auto& f : run["frames"]) {
    if (f["flat_boxes"].get<int>() > 0) flat_frames.insert(f["index"].get<uint64_t>());
  }
  const auto header = mapdb::read_map_header(db);
  map::Map map;
  auto camera = std::make_shared<const geometry::PinholeCamera>(header.identity.camera);
  auto levels = std::make_shared<const map::ScaleLevels>(static_cast<float>(header.identity.orb_scale_factor),
                                                         header.identity.orb_levels);
  mapdb::load_map(db, header.identity, map, camera, levels, nullptr);
  PointsInBoxes count;
  for (const auto& kf : map.keyframes()) {
    const auto it = boxes.find(kf->frame_id);
    if (it == boxes.end()) continue;
    ++count.frames_with_people;
    for (const auto& point : kf->valid_map_points()) {
      const auto index = static_cast<size_t>(point->index_in(kf->id));
      const cv::Point2f p = kf->features->keys[index].pt;
      ++count.checked;
      for (const auto& box : it->second) {
        if (!box.contains(p)) continue;
        ++count.inside;
        if (flat_frames.count(kf->frame_id)) ++count.inside_flat;
        break;
      }
    }
  }
  return count;
}
}  // namespace

TEST(MapRoundTrip, NoMapPointIsObservedInsideAPersonBox) {
  test::TempDir tmp;
  const auto room = test::make_room(tmp, 3);
  const auto people_gt = room / "people_gt.txt";
  // The paper filter with ground-truth boxes, the flat-box test off: no keyframe maps a keypoint in a box.
  auto options = test::run_options(room, tmp / "crowd");
  options.people_filter = true;
  options.filter_mode = "paper";
  options.detections_file = people_gt.string();
  options.save_map = (tmp / "crowd.db").string();
  options.settings_path = (tmp / "no_flat.yaml").string();
  test::write_text(options.settings_path,
                   test::read_text(room / "settings.yaml") + "\nPeopleFilter.flat_box_margin_m: 0\n");
  const auto plain = run::run_sequence(options);
  const PointsInBoxes strict = points_in_boxes(tmp / "crowd.db", people_gt, plain.json);
  EXPECT_GT(strict.frames_with_people, 2u);
  EXPECT_GT(strict.checked, 500u);
  EXPECT_EQ(strict.inside, 0u);

  // With the RGB-D default the depth test (people/box_depth.h) drops the boxes of people who have nothing
  // standing out around them (here: walking past the walls), and their keypoints are used like any
  // other: every map point inside a box is in a frame where the run reported a flat box.
  auto with_flat = test::run_options(room, tmp / "crowd_flat");
  with_flat.people_filter = true;
  with_flat.filter_mode = "paper";
  with_flat.detections_file = people_gt.string();
  with_flat.save_map = (tmp / "crowd_flat.db").string();
  const auto flat_run = run::run_sequence(with_flat);
  const PointsInBoxes loose = points_in_boxes(tmp / "crowd_flat.db", people_gt, flat_run.json);
  EXPECT_GT(flat_run.json["people_filter"]["flat_boxes"].get<int>(), 0);
  EXPECT_EQ(loose.inside, loose.inside_flat);
}
