// Crowd profiles (synth/crowd.h): 30 people find room, walkers keep their distances and cross the view,
// groups stand together, near crossers come close, and the blackout group covers the view.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "crowdslam/synth/crowd.h"
#include "crowdslam/synth/render.h"
#include "crowdslam/synth/scene.h"
#include "crowdslam/util/error.h"
#include "synth_test_util.h"
#include "test_support.h"

namespace crowdslam::synth {
namespace {

SynthOptions crowd_options(CrowdProfile profile, int people, int frames, std::uint64_t seed = 5) {
  SynthOptions o;
  o.width = 160;
  o.height = 120;
  o.frames = frames;
  o.people = people;
  o.crowd = profile;
  o.seed = seed;
  o.texture_dir = "";
  return o;
}

double camera_distance(const Scene& scene, const PersonTrack& t, int f) {
  return (t.states[f].position - scene.trajectory()[f].world_from_cam.translation().head<2>()).norm();
}

bool on_the_floor(const Scene& scene, const Eigen::Vector2d& p) {
  const WalkArea& a = scene.walk_area();
  if (p.x() < a.min_corner.x() + 0.3 || p.x() > a.max_corner.x() - 0.3 || p.y() < a.min_corner.y() + 0.3 ||
      p.y() > a.max_corner.y() - 0.3) {
    return false;
  }
  for (const auto& [lo, hi] : a.obstacles) {
    if (p.x() > lo.x() - 0.28 && p.x() < hi.x() + 0.28 && p.y() > lo.y() - 0.28 && p.y() < hi.y() + 0.28)
      return false;
  }
  return true;
}

TEST(SynthCrowd, ThirtyPeopleFindRoomAndWalkersKeepTheirDistances) {
  for (const TrajectoryKind kind : {TrajectoryKind::kLoop, TrajectoryKind::kSweep}) {
    SynthOptions o = crowd_options(CrowdProfile::kPassing, 30, 300);
    o.trajectory = kind;
    const Scene scene = Scene::build(o);
    SCOPED_TRACE(to_string(kind));
    EXPECT_NEAR(o.room_scale(), std::sqrt(30.0 / 12.0), 1e-12);
    EXPECT_NEAR(scene.static_boxes()[0].half.x(), 3.0 * o.room_scale(), 1e-9) << "the room grows for 30";
    ASSERT_EQ(scene.people().size(), 30u);
    int walking = 0;
    double min_spacing = 1e9;
    double min_camera = 1e9;
    for (const PersonTrack& t : scene.people()) {
      ASSERT_EQ(t.role, PersonRole::kWalker);
      double walked = 0.0;
      for (int f = 0; f < scene.frame_count(); ++f) {
        ASSERT_TRUE(on_the_floor(scene, t.states[f].position)) << "person " << t.id << " frame " << f;
        min_camera = std::min(min_camera, camera_distance(scene, t, f));
        for (const PersonTrack& u : scene.people()) {
          if (u.id > t.id)
            min_spacing = std::min(min_spacing, (t.states[f].position - u.states[f].position).norm());
        }
        if (f > 0) {
          const double step = (t.states[f].position - t.states[f - 1].position).norm();
          ASSERT_LE(step, t.speed_mps / kFps + 1e-9);
          walked += step;
        }
      }
      walking += walked > 0.3 * t.speed_mps * scene.frame_count() / kFps;
    }
    EXPECT_GE(min_spacing, kCrowdSpacingM - 1e-9);
    EXPECT_GE(min_camera, kWalkerCameraDistanceM - 0.05);
    EXPECT_GE(walking, 24) << "most of the 30 walk most of the time (some stop for a while)";
  }
  // Bounds of the option itself.
  SynthOptions too_many = crowd_options(CrowdProfile::kPassing, 51, 10);
  EXPECT_THROW(too_many.check(), InputError);
  EXPECT_THROW(parse_crowd_profile("stampede"), InputError);
  EXPECT_EQ(parse_crowd_profile("blackout"), CrowdProfile::kBlackout);
  EXPECT_EQ(crowd_options(CrowdProfile::kWalk, 30, 10).room_scale(), 1.0) << "walk keeps the room of before";
}

// Walkers cross the view: the sign of their offset to the camera's right flips while they are in front.
int crossings(const Scene& scene, const PersonTrack& t) {
  int flips = 0;
  int last_side = 0;
  for (int f = 0; f < scene.frame_count(); ++f) {
    const geometry::SE3& pose = scene.trajectory()[f].world_from_cam;
    const Eigen::Vector3d p =
        pose.inverse() * Eigen::Vector3d(t.states[f].position.x(), t.states[f].position.y(), 1.0);
    if (p.z() < 0.5 || p.z() > 4.0 || std::abs(p.x()) > 0.7 * p.z()) continue;  // not in front, in view
    const int side = p.x() > 0 ? 1 : -1;
    flips += last_side != 0 && side != last_side;
    last_side = side;
  }
  return flips;
}

TEST(SynthCrowd, PassingWalkersCrossTheViewMoreThanWalkers) {
  // The line trajectory hardly turns, so the crossings are the people's own.
  SynthOptions o = crowd_options(CrowdProfile::kPassing, 10, 600);
  o.trajectory = TrajectoryKind::kLine;
  const Scene passing = Scene::build(o);
  o.crowd = CrowdProfile::kWalk;
  const Scene walk = Scene::build(o);
  int passing_crossings = 0;
  int walk_crossings = 0;
  int stops = 0;
  for (const PersonTrack& t : passing.people()) {
    passing_crossings += crossings(passing, t);
    for (int f = 31; f < passing.frame_count(); ++f) {  // standing still a second after walking
      const bool still = (t.states[f].position - t.states[f - 30].position).norm() < 1e-9;
      const bool was_walking = (t.states[f - 30].position - t.states[f - 31].position).norm() > 1e-4;
      stops += still && was_walking;
    }
  }
  for (const PersonTrack& t : walk.people()) walk_crossings += crossings(walk, t);
  EXPECT_GE(passing_crossings, 25);
  EXPECT_GT(passing_crossings, 1.3 * walk_crossings);
  EXPECT_GE(stops, 2) << "walkers stop now and then";
}

TEST(SynthCrowd, StandingGroupsStandTogetherClearOfTheCamera) {
  const Scene scene = Scene::build(crowd_options(CrowdProfile::kStanding, 12, 300));
  int members = 0;
  for (const PersonTrack& t : scene.people()) {
    if (t.role != PersonRole::kGroup) continue;
    ++members;
    double nearest_member = 1e9;
    for (const PersonTrack& u : scene.people()) {
      if (u.id != t.id && u.role == PersonRole::kGroup) {
        nearest_member = std::min(nearest_member, (t.states[0].position - u.states[0].position).norm());
      }
    }
    EXPECT_LT(nearest_member, 0.8) << "person " << t.id << " stands with others";
    EXPECT_GE(nearest_member, kCrowdSpacingM - 1e-9);
    for (int f = 0; f < scene.frame_count(); ++f) {
      EXPECT_LT((t.states[f].position - t.states[0].position).norm(), 0.05) << "stands, swaying a little";
      EXPECT_GE(camera_distance(scene, t, f), 0.7 - 1e-9) << "the camera passes groups at 0.7 m or more";
      ASSERT_TRUE(on_the_floor(scene, t.states[f].position));
    }
  }
  EXPECT_GE(members, 8) << "three quarters of 12 stand in groups";
}

TEST(SynthCrowd, NearCrossersComeCloseToTheCameraOthersDoNot) {
  const Scene scene = Scene::build(crowd_options(CrowdProfile::kNear, 6, 600));
  int near = 0;
  for (const PersonTrack& t : scene.people()) {
    double closest = 1e9;
    for (int f = 0; f < scene.frame_count(); ++f) closest = std::min(closest, camera_distance(scene, t, f));
    if (t.role == PersonRole::kNear) {
      ++near;
      EXPECT_GE(closest, kNearCameraDistanceM - 0.05) << "person " << t.id;
      EXPECT_LT(closest, 0.7) << "person " << t.id;
    } else {
      EXPECT_GE(closest, kWalkerCameraDistanceM - 0.05) << "person " << t.id;
    }
  }
  EXPECT_EQ(near, 2);
}

TEST(SynthCrowd, TheBlackoutGroupCoversTheViewOnceForOneAndAHalfSeconds) {
  crowdslam::test::TempDir tmp;
  test::write_test_sprites(tmp / "s", 8);
  SynthOptions o = crowd_options(CrowdProfile::kBlackout, 9, 240);
  o.sprite_dir = (tmp / "s").string();
  const Scene scene = Scene::build(o);
  const auto [first, last] = scene.blackout_frames();
  ASSERT_GE(first, 0);
  EXPECT_EQ(last - first + 1, static_cast<int>(std::lround(kBlackoutSeconds * kFps)));
  EXPECT_GE(first, 0.3 * o.frames - 1);
  EXPECT_LE(last, o.frames - 1);
  int covered = 0;
  for (int f = first; f <= last; ++f) {
    const RenderedFrame r = render_frame(scene, f);
    const double coverage = cv::countNonZero(r.person_label) / static_cast<double>(r.person_label.total());
    covered += coverage >= 0.95;
  }
  EXPECT_GE(covered, 0.8 * (last - first + 1)) << "people fill (nearly) the whole view";
  // Well before and after, the view is clear of them.
  for (int f : {std::max(0, first - 60), std::min(o.frames - 1, last + 60)}) {
    const RenderedFrame r = render_frame(scene, f);
    int blackout_pixels = 0;
    for (const PersonTrack& t : scene.people()) {
      if (t.role == PersonRole::kBlackout) blackout_pixels += cv::countNonZero(r.person_label == t.id);
    }
    EXPECT_LT(blackout_pixels, 0.3 * r.person_label.total()) << "frame " << f;
  }
}

}  // namespace
}  // namespace crowdslam::synth

namespace crowdslam::synth {
namespace {

TEST(SynthCrowd, HiddenPeopleLeaveTheSameRoomAndCameraWithoutAnyPerson) {
  SynthOptions shown = crowd_options(CrowdProfile::kPassing, 16, 30);
  SynthOptions hidden = shown;
  hidden.hide_people = true;
  const Scene a = Scene::build(shown);
  const Scene b = Scene::build(hidden);
  EXPECT_EQ(a.options().room_scale(), b.options().room_scale());  // the crowd's room, not the empty one's
  ASSERT_EQ(a.static_boxes().size(), b.static_boxes().size());
  EXPECT_NEAR((a.static_boxes()[0].half - b.static_boxes()[0].half).norm(), 0.0, 1e-12);
  ASSERT_EQ(a.trajectory().size(), b.trajectory().size());
  for (size_t f = 0; f < a.trajectory().size(); ++f) {
    EXPECT_NEAR((a.trajectory()[f].world_from_cam.translation() - b.trajectory()[f].world_from_cam.translation()).norm(),
                0.0, 1e-12);
  }
  size_t shown_people = 0;
  for (int f = 0; f < 30; ++f) {
    shown_people += a.moving_boxes(f).size() + a.people_billboards(f).size();
    EXPECT_TRUE(b.moving_boxes(f).empty());
    EXPECT_TRUE(b.people_billboards(f).empty());
  }
  EXPECT_GE(shown_people, 16u * 30u);  // box people or billboards, one per person and frame
}

}  // namespace
}  // namespace crowdslam::synth
