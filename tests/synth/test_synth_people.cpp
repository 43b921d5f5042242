// People: walking limits, camera clearance, and the MOT boxes against the rendered label map.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "crowdslam/synth/render.h"
#include "crowdslam/synth/writer.h"

namespace crowdslam::synth {
namespace {

Scene people_scene(int frames, int people, TrajectoryKind kind = TrajectoryKind::kLoop) {
  SynthOptions o;
  o.width = 160;
  o.height = 120;
  o.frames = frames;
  o.people = people;
  o.trajectory = kind;
  o.seed = 7;
  return Scene::build(o);
}

TEST(SynthPeople, WalkAtHumanSpeedInsideTheRoomAwayFromTheCamera) {
  for (TrajectoryKind kind : {TrajectoryKind::kLoop, TrajectoryKind::kLine, TrajectoryKind::kSweep}) {
    const Scene scene = people_scene(300, 4, kind);
    ASSERT_EQ(scene.people().size(), 4u);
    for (const PersonTrack& track : scene.people()) {
      EXPECT_GE(track.speed_mps, 0.5);
      EXPECT_LE(track.speed_mps, 1.2);
      ASSERT_EQ(static_cast<int>(track.states.size()), scene.frame_count());
      double walked_m = 0.0;
      for (int f = 0; f < scene.frame_count(); ++f) {
        const PersonState& s = track.states[f];
        const Eigen::Vector2d camera = scene.trajectory()[f].world_from_cam.translation().head<2>();
        EXPECT_GE(distance_to_person(s, camera), 0.65) << "person " << track.id << " frame " << f;
        for (const Eigen::Vector3d& corner : person_box(s, track.id).corners()) {
          EXPECT_GT(corner.x(), -3.0);
          EXPECT_LT(corner.x(), 3.0);
          EXPECT_GT(corner.y(), -2.5);
          EXPECT_LT(corner.y(), 2.5);
        }
        if (f > 0) {
          const double step = (s.position - track.states[f - 1].position).norm();
          EXPECT_LE(step, track.speed_mps / kFps + 1e-9);
          walked_m += step;
        }
      }
      EXPECT_GT(walked_m, 0.5 * track.speed_mps * scene.frame_count() / kFps) << "people mostly walk";
    }
  }
}

TEST(SynthPeople, BoxesContainTheirPixelsAndAreTightWhenUnoccluded) {
  const Scene scene = people_scene(300, 4);
  const Intrinsics& k = scene.intrinsics();
  int unoccluded_checked = 0;
  int frames_with_people = 0;
  double max_coverage = 0.0;
  for (int f = 0; f < scene.frame_count(); f += 3) {
    const geometry::SE3& pose = scene.trajectory()[f].world_from_cam;
    const RenderedFrame r = render_frame(scene, f);
    const std::vector<PersonBox> boxes = visible_person_boxes(scene, r, pose, f);
    if (!boxes.empty()) ++frames_with_people;
    max_coverage = std::max(max_coverage, cv::countNonZero(r.person_label) / static_cast<double>(k.width * k.height));
    for (const Box& person : scene.people_boxes(f)) {
      const auto it = std::find_if(boxes.begin(), boxes.end(), [&](const PersonBox& b) { return b.id == person.person_id; });
      // Label pixels of this person and its unoccluded silhouette (ray cast against its box alone).
      int min_u = k.width, min_v = k.height, max_u = -1, max_v = -1;
      int label_pixels = 0;
      int silhouette_pixels = 0;
      const Eigen::Vector3d origin = person.to_local(pose.translation());
      for (int v = 0; v < k.height; ++v) {
        for (int u = 0; u < k.width; ++u) {
          const Eigen::Vector3d dir = pose.rotation_matrix() * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
          if (intersect_local(person, origin, person.dir_to_local(dir))) ++silhouette_pixels;
          if (r.person_label.at<std::uint16_t>(v, u) != person.person_id) continue;
          ++label_pixels;
          min_u = std::min(min_u, u);
          max_u = std::max(max_u, u);
          min_v = std::min(min_v, v);
          max_v = std::max(max_v, v);
          ASSERT_NE(it, boxes.end()) << "visible person " << person.person_id << " has no box in frame " << f;
          EXPECT_GE(u, it->box.x - 1e-6);
          EXPECT_LE(u, it->box.x + it->box.width + 1e-6);
          EXPECT_GE(v, it->box.y - 1e-6);
          EXPECT_LE(v, it->box.y + it->box.height + 1e-6);
        }
      }
      if (label_pixels == 0) {
        EXPECT_EQ(it, boxes.end()) << "invisible person " << person.person_id << " listed in frame " << f;
        continue;
      }
      if (label_pixels == silhouette_pixels) {  // nothing in front of the person
        ++unoccluded_checked;
        EXPECT_NEAR(min_u, it->box.x, 2.0);
        EXPECT_NEAR(min_v, it->box.y, 2.0);
        EXPECT_NEAR(max_u, it->box.x + it->box.width, 2.0);
        EXPECT_NEAR(max_v, it->box.y + it->box.height, 2.0);
      }
    }
  }
  EXPECT_GT(unoccluded_checked, 10);
  EXPECT_GT(frames_with_people, 20);
  EXPECT_GT(max_coverage, 0.2) << "people should sometimes fill a large part of the view";
}

}  // namespace
}  // namespace crowdslam::synth
