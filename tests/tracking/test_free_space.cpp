// The dynamic check's free-space test (DynamicCheck::free_space, RGB-D): an unmatched map point that the
// depth image sees through is culled; one whose surface is there, hidden behind something nearer or at a
// depth edge is not. Frames and depth images built in closed form.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/dynamic_check.h"
#include "tracking_test_camera.h"

using namespace crowdslam;
using namespace crowdslam::tracking;

namespace {

constexpr double kUnitsPerMetre = 5000.0;  // TUM / Bonn depth scale

std::shared_ptr<geometry::PinholeCamera> camera() { return test::rgbd_test_camera(); }

const auto kLevels = std::make_shared<map::ScaleLevels>(1.2f, 8);

// A keyframe at the identity pose with one keypoint per point, at the point's projection (level 0), so
// that the points' viewing ranges (update_normal_and_depth) are those of an observation from here.
std::shared_ptr<map::KeyFrame> keyframe_seeing(const std::vector<geometry::Vec3>& world) {
  const auto cam = camera();
  auto f = std::make_shared<map::FrameFeatures>();
  for (const auto& w : world) {
    const geometry::Vec2 px = cam->project(w);
    cv::KeyPoint k(cv::Point2f(static_cast<float>(px.x()), static_cast<float>(px.y())), 31.0f, 0, 1, 0);
    f->keys.push_back(k);
    f->keys_un.push_back(k);
    f->depth_m.push_back(static_cast<float>(w.z()));
    f->right_u.push_back(static_cast<float>(px.x() - cam->bf / w.z()));
  }
  f->descriptors = cv::Mat::zeros(static_cast<int>(world.size()), 32, CV_8UC1);
  f->grid = map::FeatureGrid(f->keys_un, geometry::ImageBounds{0, 640, 0, 480});
  return std::make_shared<map::KeyFrame>(0, 0, 0.0, cam, kLevels, f, geometry::SE3::identity());
}

std::vector<std::shared_ptr<map::MapPoint>> map_points(const std::vector<geometry::Vec3>& world,
                                                       const std::shared_ptr<map::KeyFrame>& kf) {
  std::vector<std::shared_ptr<map::MapPoint>> points;
  for (size_t i = 0; i < world.size(); ++i) {
    auto p = std::make_shared<map::MapPoint>(i, world[i], kf, 0);
    p->add_observation(kf, i);
    p->update_normal_and_depth();
    points.push_back(std::move(p));
  }
  return points;
}

// A frame at the identity pose with no keypoints of its own (nothing matched) and the given depth image.
map::Frame frame_with_depth(uint64_t id, const cv::Mat& depth_raw) {
  auto f = std::make_shared<map::FrameFeatures>();
  f->descriptors = cv::Mat::zeros(0, 32, CV_8UC1);
  f->grid = map::FeatureGrid(f->keys_un, geometry::ImageBounds{0, 640, 0, 480});
  map::Frame frame(id, 0.1 * static_cast<double>(id), camera(), kLevels, f);
  frame.cam_from_world = geometry::SE3::identity();
  frame.depth_raw = depth_raw;
  frame.depth_metres_per_unit = 1.0 / kUnitsPerMetre;
  return frame;
}

cv::Mat depth_image(double metres) {
  return cv::Mat(480, 640, CV_16UC1, cv::Scalar(static_cast<uint16_t>(metres * kUnitsPerMetre)));
}

}  // namespace

TEST(FreeSpace, APointTheDepthImageSeesThroughIsCulledAfterTwoFramesInARow) {
  // Points at 2 m; the sensor sees a wall at 3 m behind them everywhere (the object they were on left).
  const std::vector<geometry::Vec3> world = {{0, 0, 2}, {0.3, 0.2, 2}, {-0.4, -0.1, 2}};
  const auto points = map_points(world, keyframe_seeing(world));
  DynamicCheck check{DynamicCheckOptions{}};  // margin max(0.2 m, 10 %), culled after 2 in a row
  DynamicCheckStats first;
  check.free_space(frame_with_depth(1, depth_image(3.0)), points, first);
  EXPECT_EQ(first.free_space, 3);
  EXPECT_EQ(first.points_culled, 0);
  for (const auto& p : points) EXPECT_FALSE(p->is_bad()) << "one frame is not enough";
  DynamicCheckStats second;
  check.free_space(frame_with_depth(2, depth_image(3.0)), points, second);
  EXPECT_EQ(second.free_space, 3);
  EXPECT_EQ(second.points_culled, 3);
  for (const auto& p : points) EXPECT_TRUE(p->is_bad());
}

TEST(FreeSpace, APointWhoseSurfaceIsThereOrHiddenIsNeverCulled) {
  const std::vector<geometry::Vec3> world = {{0, 0, 2}, {0.3, 0.2, 2}};
  const auto points = map_points(world, keyframe_seeing(world));
  DynamicCheck check{DynamicCheckOptions{}};
  DynamicCheckStats stats;
  for (uint64_t id = 1; id <= 10; ++id) {
    // Its own surface within the margin (2.15 m: depth noise), then something nearer (a person at 1 m).
    check.free_space(frame_with_depth(id, depth_image(id % 2 ? 2.15 : 1.0)), points, stats);
  }
  EXPECT_EQ(stats.free_space, 0);
  for (const auto& p : points) EXPECT_FALSE(p->is_bad());
}

TEST(FreeSpace, NoVerdictAtADepthEdgeWithoutDepthOrForMatchedPoints) {
  const std::vector<geometry::Vec3> world = {{0, 0, 2}};
  const auto points = map_points(world, keyframe_seeing(world));
  DynamicCheck check{DynamicCheckOptions{}};
  DynamicCheckStats stats;
  // A depth edge through the projection (a foreground object at 2 m left of column 320, wall at 5 m to
  // the right): a pixel or two of pose error would put the point on the wall, so the window sees both.
  cv::Mat edge = depth_image(5.0);
  edge(cv::Rect(0, 0, 320, 480)).setTo(cv::Scalar(2.0 * kUnitsPerMetre));
  check.free_space(frame_with_depth(1, edge), points, stats);
  check.free_space(frame_with_depth(2, edge), points, stats);
  // No depth at all around it (0 = no measurement).
  check.free_space(frame_with_depth(3, cv::Mat::zeros(480, 640, CV_16UC1)), points, stats);
  check.free_space(frame_with_depth(4, cv::Mat::zeros(480, 640, CV_16UC1)), points, stats);
  // Matched in the frame: the verdicts of update() apply, not this test.
  map::Frame matched = frame_with_depth(5, depth_image(5.0));
  matched.map_points = {points[0]};
  check.free_space(matched, points, stats);
  check.free_space(matched, points, stats);
  // Off (margin 0), and without a depth image (monocular / stereo).
  DynamicCheckOptions off;
  off.free_space_margin_m = 0;
  DynamicCheck unchecked{off};
  unchecked.free_space(frame_with_depth(6, depth_image(5.0)), points, stats);
  unchecked.free_space(frame_with_depth(7, depth_image(5.0)), points, stats);
  check.free_space(frame_with_depth(8, cv::Mat()), points, stats);
  check.free_space(frame_with_depth(9, cv::Mat()), points, stats);
  EXPECT_EQ(stats.free_space, 0);
  EXPECT_FALSE(points[0]->is_bad());
}

TEST(FreeSpace, AMatchedObservationBetweenTwoSeenThroughOnesKeepsThePoint) {
  // Two in a row are needed: a static verdict in between (the point was matched and did not move) resets.
  const std::vector<geometry::Vec3> world = {{0, 0, 2}};
  const auto points = map_points(world, keyframe_seeing(world));
  DynamicCheck check{DynamicCheckOptions{}};
  DynamicCheckStats stats;
  for (uint64_t id = 1; id <= 6; ++id) {
    check.free_space(frame_with_depth(id, depth_image(3.0)), points, stats);
    points[0]->record_motion(false);
  }
  EXPECT_EQ(stats.free_space, 6);
  EXPECT_FALSE(points[0]->is_bad());
}

TEST(Camera, DistortPixelIsOpenCvsForwardModel) {
  // cv::projectPoints applies the plumb-bob model forwards (exact, no iteration), the model the
  // undistortion inverts.
  auto cam = camera();
  cam->distortion.k1 = -0.28;
  cam->distortion.k2 = 0.07;
  cam->distortion.p1 = 0.0002;
  cam->distortion.p2 = 0.00002;
  cam->distortion.k3 = 0.01;
  const cv::Mat k = (cv::Mat_<double>(3, 3) << cam->fx, 0, cam->cx, 0, cam->fy, cam->cy, 0, 0, 1);
  const cv::Mat d = (cv::Mat_<double>(1, 5) << -0.28, 0.07, 0.0002, 0.00002, 0.01);
  for (const geometry::Vec2 undistorted : {geometry::Vec2(10, 12), geometry::Vec2(420, 300), geometry::Vec2(600, 400),
                                           geometry::Vec2(100, 450)}) {
    const geometry::Vec2 n = cam->normalize(undistorted);
    std::vector<cv::Point2d> expected;
    cv::projectPoints(std::vector<cv::Point3d>{{n.x(), n.y(), 1.0}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, d,
                      expected);
    const geometry::Vec2 raw = cam->distort_pixel(undistorted);
    EXPECT_NEAR(raw.x(), expected[0].x, 1e-6);
    EXPECT_NEAR(raw.y(), expected[0].y, 1e-6);
    EXPECT_GT((raw - undistorted).norm(), 0.5) << "the distortion moves these pixels";
  }
  auto plain = camera();
  EXPECT_EQ(plain->distort_pixel({123.25, 45.5}), geometry::Vec2(123.25, 45.5));
}
