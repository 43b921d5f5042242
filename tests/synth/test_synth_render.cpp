// Rendering is geometrically and photometrically consistent with the ground-truth poses and intrinsics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/synth/render.h"
#include "synth_test_util.h"

namespace crowdslam::synth {
namespace {

Scene small_scene(TrajectoryKind kind, int frames, int people, std::uint64_t seed = 1) {
  SynthOptions o;
  o.width = 160;
  o.height = 120;
  o.frames = frames;
  o.people = people;
  o.trajectory = kind;
  o.seed = seed;
  return Scene::build(o);
}

void expect_consistent(const Scene& scene, int i, int j) {
  const RenderedFrame a = render_frame(scene, i);
  const RenderedFrame b = render_frame(scene, j);
  const auto c = test::check_consistency(a.colour, a.depth_m, a.person_label, scene.trajectory()[i].world_from_cam,
                                         b.colour, b.depth_m, b.person_label, scene.trajectory()[j].world_from_cam,
                                         scene.intrinsics(), 1);
  SCOPED_TRACE("frames " + std::to_string(i) + " -> " + std::to_string(j));
  ASSERT_GT(c.inside, c.sampled / 3) << "frames should overlap";
  EXPECT_GT(c.depth_agrees, 0.85 * c.inside);
  EXPECT_LT(c.median_grey_diff, 4.0);
}

TEST(SynthRender, FramesAreConsistentWithPosesAndDepth) {
  const Scene loop = small_scene(TrajectoryKind::kLoop, 150, 2);
  for (int i : {0, 40, 100}) expect_consistent(loop, i, i + 5);
  const Scene sweep = small_scene(TrajectoryKind::kSweep, 60, 0);
  for (int i : {0, 30, 50}) expect_consistent(sweep, i, i + 5);
}

TEST(SynthRender, WrongPoseIsDetectedByTheConsistencyCheck) {
  // Guards the check itself: a pose offset by 10 cm must break depth agreement.
  const Scene scene = small_scene(TrajectoryKind::kLoop, 150, 0);
  const RenderedFrame a = render_frame(scene, 10);
  const RenderedFrame b = render_frame(scene, 15);
  const geometry::SE3 shifted = scene.trajectory()[15].world_from_cam *
                                geometry::SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0.0, 0.0));
  const auto c = test::check_consistency(a.colour, a.depth_m, a.person_label, scene.trajectory()[10].world_from_cam,
                                         b.colour, b.depth_m, b.person_label, shifted, scene.intrinsics(), 1);
  EXPECT_LT(c.depth_agrees, 0.5 * c.inside);
}

TEST(SynthRender, DepthIsTheZDistanceToTheHitSurface) {
  // Looking straight along a room axis the wall depth is known in closed form.
  const Scene scene = small_scene(TrajectoryKind::kLine, 5, 0);
  // Camera at the origin 1 m up, looking along +x (yaw 0, level): the +x wall is at x = 3.
  const geometry::SE3 pose(Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
                                              Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX())),
                           Eigen::Vector3d(0.0, 0.0, 1.0));
  // Sanity of the constructed pose: camera z axis = world +x.
  ASSERT_NEAR((pose.rotation_matrix().col(2) - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-12);
  const RenderedFrame f = render(scene, pose, {});
  // The centre rows near the middle see the +x wall (x = 3) unless an obstacle is there: the pillar at
  // x 1.7-2.1 is at y 1.3-1.7, off the optical axis; nothing else is between.
  const int cy = static_cast<int>(scene.intrinsics().cy);
  const int cx = static_cast<int>(scene.intrinsics().cx);
  EXPECT_NEAR(f.depth_m.at<float>(cy, cx), 3.0, 1e-4);
  EXPECT_NEAR(f.depth_m.at<float>(cy - 20, cx + 30), 3.0, 1e-4);  // z-depth, not ray length
  // The bottom row sees the floor 1 m below: depth = 1 * fy / (v - cy).
  const int v = static_cast<int>(scene.intrinsics().height - 1);
  const double expected = 1.0 * scene.intrinsics().fy / (v - scene.intrinsics().cy);
  ASSERT_LT(expected, 3.0);
  EXPECT_NEAR(f.depth_m.at<float>(v, cx), expected, 1e-4);
}

TEST(SynthRender, StereoPairIsRectifiedWithTheBaseline) {
  const Scene scene = small_scene(TrajectoryKind::kLoop, 150, 0);
  const Intrinsics& k = scene.intrinsics();
  for (int frame : {0, 60}) {
    const RenderedFrame left = render_frame(scene, frame, false);
    const RenderedFrame right = render_frame(scene, frame, true);
    // A left pixel at depth d appears in the right image at u - fx * b / d on the same row.
    const auto c = test::check_consistency(left.colour, left.depth_m, {}, scene.trajectory()[frame].world_from_cam,
                                           right.colour, right.depth_m, {}, scene.right_world_from_cam(frame), k, 1);
    EXPECT_GT(c.depth_agrees, 0.9 * c.inside);
    EXPECT_LT(c.median_grey_diff, 4.0);
    const geometry::SE3 right_from_left = scene.right_world_from_cam(frame).inverse() *
                                          scene.trajectory()[frame].world_from_cam;
    EXPECT_NEAR((right_from_left.translation() - Eigen::Vector3d(-kStereoBaselineM, 0, 0)).norm(), 0.0, 1e-12);
    EXPECT_NEAR(geometry::rotation_angle(right_from_left.rotation_matrix()), 0.0, 1e-12);
  }
}

TEST(SynthRender, TexturesGiveManyWellSpreadFastCorners) {
  // No blurry smear: a full-size frame has plenty of FAST corners (ORB's detector, its default
  // threshold 20) spread over most of the image.
  SynthOptions photos;
  SynthOptions procedural;
  procedural.texture_dir = "";  // the fallback when opencv-doc's photographs are missing
  for (const auto& [options, frame] : {std::pair{photos, 0}, std::pair{photos, 120}, std::pair{procedural, 250}}) {
    const Scene scene = Scene::build(options);
    EXPECT_EQ(scene.photo_textures(), !options.texture_dir.empty());
    const RenderedFrame f = render_frame(scene, frame);
    cv::Mat grey;
    cv::cvtColor(f.colour, grey, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> corners;
    cv::FAST(grey, corners, 20, true);
    EXPECT_GT(corners.size(), 1000u) << "frame " << frame;
    std::vector<bool> cell_has_corner(8 * 6, false);  // 80x80 px cells
    for (const auto& kp : corners) cell_has_corner[static_cast<int>(kp.pt.y / 80) * 8 + static_cast<int>(kp.pt.x / 80)] = true;
    EXPECT_GE(std::count(cell_has_corner.begin(), cell_has_corner.end(), true), 40) << "frame " << frame;
  }
}

}  // namespace
}  // namespace crowdslam::synth
