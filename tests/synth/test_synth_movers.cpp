// Movers (synth/movers.h): moving non-person objects, their moving-pixel mask, and their clearance from
// the camera, the obstacles and the people.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "crowdslam/synth/movers.h"
#include "crowdslam/synth/render.h"
#include "crowdslam/synth/scene.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::synth {
namespace {
namespace fs = std::filesystem;

SynthOptions options(int movers, int people = 0) {
  SynthOptions o;
  o.width = 160;
  o.height = 120;
  o.frames = 240;
  o.movers = movers;
  o.people = people;
  o.texture_dir = "";  // procedural textures: fast
  return o;
}

TEST(SynthMovers, EachKindMovesAsDescribed) {
  const auto movers = make_movers(kMaxMovers);
  ASSERT_EQ(movers.size(), 4u);
  for (const Mover& m : movers) {
    const Box a = m.box_at(0.0);
    const Box b = m.box_at(0.5 * m.period_s);
    const Box c = m.box_at(m.period_s);
    EXPECT_GT((a.center - b.center).norm(), 0.3) << to_string(m.kind) << " " << m.id;
    EXPECT_NEAR((a.center - c.center).norm(), 0.0, 1e-9) << "periodic";
    EXPECT_EQ(a.mover_id, m.id);
    EXPECT_EQ(a.person_id, 0);
    if (m.kind == MoverKind::kDoor) {
      // The hinge edge stays where it is: the panel's -x edge at the hinge for every opening angle.
      for (double t : {0.0, 0.3, 1.1, 2.0}) {
        const Box d = m.box_at(t);
        const Eigen::Vector2d edge = d.center.head<2>() - d.half.x() * Eigen::Vector2d(std::cos(d.yaw), std::sin(d.yaw));
        EXPECT_NEAR((edge - m.start).norm(), 0.0, 1e-9);
      }
      EXPECT_NEAR(std::abs(b.yaw - a.yaw), std::abs(m.swing), 1e-9);
    }
  }
  EXPECT_THROW(make_movers(kMaxMovers + 1), InputError);
  EXPECT_THROW(make_movers(-1), InputError);
  SynthOptions bad = options(5);
  EXPECT_THROW(bad.check(), InputError);
}

TEST(SynthMovers, MaskIsExactlyWhereAMoverHidesTheStaticScene) {
  // Rendered with and without the movers: the depth differs exactly where the mask says something moves.
  const Scene scene = Scene::build(options(kMaxMovers));
  int masked_total = 0;
  for (int frame = 0; frame < scene.frame_count(); frame += 20) {
    const geometry::SE3& pose = scene.trajectory()[frame].world_from_cam;
    const RenderedFrame with = render(scene, pose, scene.moving_boxes(frame));
    const RenderedFrame without = render(scene, pose, {});
    for (int v = 0; v < with.moving.rows; ++v) {
      for (int u = 0; u < with.moving.cols; ++u) {
        const bool masked = with.moving.at<uint8_t>(v, u) == 255;
        const bool nearer = with.depth_m.at<float>(v, u) < without.depth_m.at<float>(v, u) - 1e-5f;
        ASSERT_EQ(masked, nearer) << "frame " << frame << " pixel " << u << "," << v;
        masked_total += masked ? 1 : 0;
      }
    }
  }
  EXPECT_GT(masked_total, 500) << "the movers are seen";
}

TEST(SynthMovers, ClearOfTheCameraTheObstaclesAndThePeople) {
  for (const TrajectoryKind kind : {TrajectoryKind::kLoop, TrajectoryKind::kLine, TrajectoryKind::kSweep, TrajectoryKind::kHandheld}) {
    SynthOptions o = options(kMaxMovers, 4);
    o.trajectory = kind;
    o.frames = 600;
    const Scene scene = Scene::build(o);
    for (int frame = 0; frame < scene.frame_count(); frame += 3) {
      const Eigen::Vector3d camera = scene.trajectory()[frame].world_from_cam.translation();
      for (const Box& b : scene.mover_boxes(frame)) {
        const Eigen::Vector3d local = b.to_local(camera);
        const Eigen::Vector3d outside = (local.cwiseAbs() - b.half).cwiseMax(0.0);
        EXPECT_GT(outside.norm(), 0.3) << to_string(kind) << " frame " << frame << " mover " << b.mover_id;
        // Inside the room.
        for (const auto& c : b.corners()) {
          EXPECT_LE(std::abs(c.x()), 3.0 + 1e-9);
          EXPECT_LE(std::abs(c.y()), 2.5 + 1e-9);
        }
      }
      for (const PersonTrack& person : scene.people()) {
        for (const Mover& m : scene.movers()) {
          const auto [lo, hi] = m.footprint();
          const Eigen::Vector2d p = person.states[frame].position;
          EXPECT_FALSE(p.x() > lo.x() && p.x() < hi.x() && p.y() > lo.y() && p.y() < hi.y())
              << "person " << person.id << " walks through mover " << m.id;
        }
      }
    }
    // No mover overlaps a static obstacle (room excluded) at any time.
    for (const Mover& m : scene.movers()) {
      const auto [lo, hi] = m.footprint();
      for (size_t i = 1; i < scene.static_boxes().size(); ++i) {
        const Box& s = scene.static_boxes()[i];
        const Eigen::Vector2d slo = (s.center - s.half).head<2>(), shi = (s.center + s.half).head<2>();
        const bool overlap = lo.x() < shi.x() && hi.x() > slo.x() && lo.y() < shi.y() && hi.y() > slo.y();
        EXPECT_FALSE(overlap) << "mover " << m.id << " and obstacle " << i;
      }
    }
  }
}

TEST(SynthMovers, WriterAddsMasksAndListsTheMovers) {
  test::TempDir tmp;
  SynthOptions o = options(3, 1);
  o.frames = 4;
  write_sequence(o, tmp / "seq");
  for (int i = 0; i < 4; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    const cv::Mat mask = cv::imread((tmp / "seq" / "mask" / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(mask.empty()) << name;
    EXPECT_EQ(mask.type(), CV_8UC1);
    EXPECT_EQ(mask.cols, 160);
    for (int v = 0; v < mask.rows; ++v)
      for (int u = 0; u < mask.cols; ++u) ASSERT_TRUE(mask.at<uint8_t>(v, u) == 0 || mask.at<uint8_t>(v, u) == 255);
  }
  const auto j = nlohmann::json::parse(test::read_text(tmp / "seq" / "synth.json"));
  ASSERT_EQ(j["movers"].size(), 3u);
  EXPECT_EQ(j["movers"][1]["kind"], "door");
  EXPECT_EQ(j["moving_mask"], "mask");
  // Without movers there is no mask folder (and the rest of the scene is the same as before movers existed).
  write_sequence(options(0), tmp / "plain");
  EXPECT_FALSE(fs::exists(tmp / "plain" / "mask"));
}

TEST(SynthMovers, MoversLeaveTheRestOfTheSceneAsItWas) {
  // Same seed with and without movers: the textures of the room and obstacles and the people's paths are
  // unchanged (only the people's detours around the movers' floor may differ, so compare without people).
  const Scene a = Scene::build(options(0));
  const Scene b = Scene::build(options(3));
  const RenderedFrame ra = render(a, a.trajectory()[0].world_from_cam, {});
  const RenderedFrame rb = render(b, b.trajectory()[0].world_from_cam, {});
  EXPECT_EQ(cv::norm(ra.colour, rb.colour, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace crowdslam::synth
