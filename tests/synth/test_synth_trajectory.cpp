// Camera trajectories: closed loops, realistic speeds, clear of the walls and obstacles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "crowdslam/synth/scene.h"
#include "crowdslam/synth/trajectory_gen.h"

namespace crowdslam::synth {
namespace {

constexpr double kDegree = M_PI / 180.0;

TEST(SynthTrajectory, LoopAndHandheldEndExactlyAtTheirStartPose) {
  for (TrajectoryKind kind : {TrajectoryKind::kLoop, TrajectoryKind::kHandheld}) {
    for (int frames : {30, 300, 451, 900}) {
      const io::Trajectory t = generate_trajectory(kind, frames, 3);
      ASSERT_EQ(static_cast<int>(t.size()), frames);
      const geometry::SE3 first = t.front().world_from_cam;
      const geometry::SE3 last = t.back().world_from_cam;
      EXPECT_LT((first.translation() - last.translation()).norm(), 1e-12);
      EXPECT_LT(geometry::rotation_angle(first.rotation_matrix().transpose() * last.rotation_matrix()), 1e-9);
      // ... and actually travels far from the start in between.
      double farthest = 0.0;
      for (const auto& pose : t) farthest = std::max(farthest, (pose.world_from_cam.translation() - first.translation()).norm());
      EXPECT_GT(farthest, 1.0);
    }
  }
}

TEST(SynthTrajectory, StampsStartAtOneSecondAt30Hz) {
  const io::Trajectory t = generate_trajectory(TrajectoryKind::kLine, 10, 1);
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(t[i].timestamp_s, 1.0 + i / 30.0, 1e-12);
}

TEST(SynthTrajectory, SpeedsAreHandheldAndTheCameraStaysClearOfObstacles) {
  SynthOptions o;
  o.width = 64;
  o.height = 48;
  const Scene scene = Scene::build(o);
  for (TrajectoryKind kind :
       {TrajectoryKind::kLoop, TrajectoryKind::kLine, TrajectoryKind::kSweep, TrajectoryKind::kHandheld}) {
    const io::Trajectory t = generate_trajectory(kind, o.frames, o.seed);
    double max_speed = 0.0;
    double max_rotation = 0.0;
    for (size_t i = 1; i < t.size(); ++i) {
      const geometry::SE3 delta = t[i - 1].world_from_cam.inverse() * t[i].world_from_cam;
      max_speed = std::max(max_speed, delta.translation().norm() * kFps);
      max_rotation = std::max(max_rotation, geometry::rotation_angle(delta.rotation_matrix()));
    }
    SCOPED_TRACE(to_string(kind));
    EXPECT_LT(max_speed, 0.7);
    EXPECT_GT(max_speed, 0.25);
    EXPECT_LT(max_rotation, 2.0 * kDegree);
    for (const auto& pose : t) {
      const Eigen::Vector3d c = pose.world_from_cam.translation();
      EXPECT_GT(c.z(), 1.0);
      EXPECT_LT(c.z(), 2.0);
      for (size_t b = 1; b < scene.static_boxes().size(); ++b) {
        const Box& box = scene.static_boxes()[b];
        const Eigen::Vector3d outside = (c - box.center).cwiseAbs() - box.half;
        EXPECT_GT(outside.cwiseMax(0.0).norm(), 0.8) << "obstacle " << b;
      }
      // The camera looks at surfaces 1-3.5 m away along its optical axis (walls it looks at).
      const Eigen::Vector3d forward = pose.world_from_cam.rotation_matrix().col(2);
      const Box& room = scene.static_boxes()[0];
      const auto hit = intersect_local(room, room.to_local(c), room.dir_to_local(forward));
      ASSERT_TRUE(hit.has_value());
      EXPECT_GT(hit->t, 1.0);
      EXPECT_LT(hit->t, 3.6);
    }
  }
}

}  // namespace
}  // namespace crowdslam::synth
