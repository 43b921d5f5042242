// The geometric dynamic check (tracking/dynamic_check.h) on frames built in closed form: points of a
// static scene observed with pixel and depth noise, and points that move between frames.
#include <gtest/gtest.h>

#include <random>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/dynamic_check.h"
#include "tracking_test_camera.h"
#include "crowdslam/util/error.h"

using namespace crowdslam;
using namespace crowdslam::tracking;

namespace {

std::shared_ptr<geometry::PinholeCamera> camera() { return test::rgbd_test_camera(); }

struct Observed {
  geometry::Vec3 cam;  // where the keypoint really is (camera frame)
  int level = 0;
};

// A frame at the identity pose whose keypoint i sees observed[i] with Gaussian pixel noise (sigma 1 px x
// the level's scale) and depth noise (sigma = 0.0015 z^2, Kinect-like), matched to points[i] (may be null).
map::Frame make_frame(uint64_t id, const std::vector<Observed>& observed,
                      const std::vector<std::shared_ptr<map::MapPoint>>& points, std::mt19937& rng, bool with_depth = true) {
  static const auto cam = camera();
  static const auto levels = std::make_shared<map::ScaleLevels>(1.2f, 8);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto f = std::make_shared<map::FrameFeatures>();
  for (const auto& o : observed) {
    const double scale = levels->scale[o.level];
    const geometry::Vec2 px = cam->project(o.cam);
    cv::KeyPoint k(cv::Point2f(static_cast<float>(px.x() + scale * gauss(rng)), static_cast<float>(px.y() + scale * gauss(rng))),
                   31.0f, 0, 1, o.level);
    f->keys.push_back(k);
    f->keys_un.push_back(k);
    const double z = o.cam.z() + 0.0015 * o.cam.z() * o.cam.z() * gauss(rng);
    f->depth_m.push_back(with_depth ? static_cast<float>(z) : -1.0f);
    f->right_u.push_back(with_depth ? static_cast<float>(k.pt.x - cam->bf / z) : -1.0f);
  }
  f->descriptors = cv::Mat::zeros(static_cast<int>(observed.size()), 32, CV_8UC1);
  f->grid = map::FeatureGrid(f->keys_un, geometry::ImageBounds{0, 640, 0, 480});
  map::Frame frame(id, 0.1 * static_cast<double>(id), cam, levels, f);
  frame.cam_from_world = geometry::SE3::identity();
  frame.map_points = points;
  return frame;
}

// A map point at `world` observed by a keyframe (so it counts as a map point, not visual odometry).
std::shared_ptr<map::MapPoint> map_point(uint64_t id, const geometry::Vec3& world,
                                         const std::shared_ptr<map::KeyFrame>& keyframe) {
  auto p = std::make_shared<map::MapPoint>(id, world, keyframe, 0);
  p->add_observation(keyframe, static_cast<size_t>(id));
  return p;
}

std::shared_ptr<map::KeyFrame> keyframe(size_t n) {
  auto f = std::make_shared<map::FrameFeatures>();
  f->keys.resize(n);
  f->keys_un.resize(n);
  f->depth_m.assign(n, 2.0f);
  f->right_u.assign(n, 300.0f);
  f->descriptors = cv::Mat::zeros(static_cast<int>(n), 32, CV_8UC1);
  f->grid = map::FeatureGrid(f->keys_un, geometry::ImageBounds{0, 640, 0, 480});
  return std::make_shared<map::KeyFrame>(0, 0, 0.0, camera(), std::make_shared<map::ScaleLevels>(1.2f, 8), f,
                                         geometry::SE3::identity());
}

geometry::Vec3 random_point(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), z(1.0, 5.0);
  const double depth = z(rng);
  return {u(rng) * 0.55 * depth, u(rng) * 0.4 * depth, depth};
}

}  // namespace

TEST(DynamicCheck, StaticPointsWithNoiseAreNotDynamic) {
  // 2000 static map points over 10 frames at levels 0-3: the false-dynamic rate must stay <= 1 %.
  std::mt19937 rng(7);
  const size_t n = 2000;
  auto kf = keyframe(n);
  std::vector<Observed> observed;
  std::vector<std::shared_ptr<map::MapPoint>> points;
  for (size_t i = 0; i < n; ++i) {
    observed.push_back({random_point(rng), static_cast<int>(i % 4)});
    points.push_back(map_point(i, observed.back().cam, kf));
  }
  DynamicCheck check{DynamicCheckOptions{}};
  std::optional<map::Frame> last;
  long dynamic = 0, judged = 0;
  for (uint64_t frame_id = 1; frame_id <= 10; ++frame_id) {
    map::Frame frame = make_frame(frame_id, observed, points, rng);
    check.inherit(frame, last ? &*last : nullptr);
    const auto stats = check.update(frame, last ? &*last : nullptr);
    // Only matches carried from the last frame get a verdict (none in the first frame).
    EXPECT_EQ(stats.checked, frame_id == 1 ? 0 : static_cast<int>(n));
    dynamic += stats.dynamic;
    judged += stats.checked;
    last = std::move(frame);
  }
  EXPECT_LE(static_cast<double>(dynamic) / static_cast<double>(judged), 0.01);
  int culled = 0;
  for (const auto& p : points) culled += p->is_bad() ? 1 : 0;
  EXPECT_LE(culled, static_cast<int>(n / 100));
}

TEST(DynamicCheck, MovingPointIsDynamicWithinThreeFramesAndCulled) {
  // 300 static points and 30 that move 3 cm per frame sideways (a walker at 0.9 m/s, 30 fps).
  std::mt19937 rng(11);
  const size_t n_static = 300, n_moving = 30;
  auto kf = keyframe(n_static + n_moving);
  std::vector<Observed> observed;
  std::vector<std::shared_ptr<map::MapPoint>> points;
  for (size_t i = 0; i < n_static + n_moving; ++i) {
    observed.push_back({random_point(rng), 0});
    points.push_back(map_point(i, observed.back().cam, kf));
  }
  DynamicCheck check{DynamicCheckOptions{}};
  std::optional<map::Frame> last;
  std::vector<int> first_dynamic(n_moving, -1);
  // A far point's first 3 cm (3 px at 5 m) are within noise; the map point stays where it was seen, so
  // the residual grows with every frame.
  for (int frame_id = 1; frame_id <= 9; ++frame_id) {
    for (size_t m = 0; m < n_moving; ++m) observed[n_static + m].cam.x() += 0.03;  // the world point moved
    map::Frame frame = make_frame(static_cast<uint64_t>(frame_id), observed, points, rng);
    check.inherit(frame, last ? &*last : nullptr);
    check.update(frame, last ? &*last : nullptr);
    for (size_t m = 0; m < n_moving; ++m) {
      if (frame.dynamic[n_static + m] && first_dynamic[m] < 0) first_dynamic[m] = frame_id;
      if (frame.dynamic[n_static + m]) EXPECT_TRUE(frame.outliers[n_static + m]);  // not a tracked point
    }
    last = std::move(frame);
  }
  for (size_t m = 0; m < n_moving; ++m) {
    EXPECT_GE(first_dynamic[m], 1) << "moving point " << m << " never marked dynamic";
    EXPECT_LE(first_dynamic[m], 3);
    EXPECT_TRUE(points[n_static + m]->is_bad()) << "seen moving in all eight checked frames: culled";
  }
  int static_culled = 0;
  for (size_t i = 0; i < n_static; ++i) static_culled += points[i]->is_bad() ? 1 : 0;
  EXPECT_LE(static_culled, 3);
}

TEST(DynamicCheck, InheritExcludesKnownMovingMatchesBeforeThePose) {
  std::mt19937 rng(3);
  auto kf = keyframe(2);
  std::vector<Observed> observed{{{0.2, 0.1, 2.0}, 0}, {{-0.3, 0.0, 3.0}, 0}};
  std::vector<std::shared_ptr<map::MapPoint>> points{map_point(0, observed[0].cam, kf), map_point(1, observed[1].cam, kf)};
  points[1]->record_motion(false);
  for (int k = 0; k < 7; ++k) points[1]->record_motion(true);
  EXPECT_EQ(points[1]->motion_score(), 7);  // 7 of the last 8: not yet
  DynamicCheck early{DynamicCheckOptions{}};
  map::Frame before = make_frame(1, observed, points, rng);
  early.inherit(before, nullptr);
  EXPECT_FALSE(before.dynamic[1]);
  points[1]->record_motion(true);  // all of the last 8: dynamic
  DynamicCheck check{DynamicCheckOptions{}};
  map::Frame frame = make_frame(1, observed, points, rng);
  check.inherit(frame, nullptr);
  EXPECT_FALSE(frame.dynamic[0]);
  EXPECT_TRUE(frame.dynamic[1]);
  // Through the last frame: a keypoint matched via a dynamic keypoint of the last frame inherits it.
  map::Frame next = make_frame(2, observed, points, rng);
  frame.dynamic[0] = true;
  check.inherit(next, &frame);
  EXPECT_TRUE(next.dynamic[0]);
  // Disabled: nothing is marked.
  DynamicCheckOptions off;
  off.enabled = false;
  DynamicCheck none{off};
  map::Frame other = make_frame(3, observed, points, rng);
  none.inherit(other, nullptr);
  EXPECT_EQ(none.update(other, nullptr).checked, 0);
  EXPECT_FALSE(other.dynamic[1]);
}

TEST(DynamicCheck, RegionsGrowToUnmatchedNeighboursAtTheSameDepth) {
  // Keypoints 0 and 6 are matched and move together; 1 is unmatched next to them at the same depth, 2
  // unmatched next to them but 1.5 m behind (the wall behind a person), 3 unmatched far away in the
  // image, 4 unmatched two steps away through 1; 5 is next to 0 but matched and static: it keeps its own
  // verdict. 7 is matched and moves alone (no cluster: a lone verdict does not spread), 8 is unmatched
  // next to it.
  std::mt19937 rng(5);
  auto kf = keyframe(9);
  std::vector<Observed> observed{{{0.0, 0.0, 2.0}, 0},   {{0.05, 0.0, 2.02}, 0}, {{0.02, 0.03, 3.5}, 0},
                                 {{0.8, 0.5, 2.0}, 0},   {{0.11, 0.0, 2.05}, 0}, {{0.07, 0.01, 2.0}, 0},
                                 {{0.01, 0.03, 2.0}, 0}, {{-0.6, -0.4, 3.0}, 0}, {{-0.57, -0.4, 3.0}, 0}};
  std::vector<std::shared_ptr<map::MapPoint>> points(9);
  for (const size_t i : {0u, 5u, 6u, 7u}) points[i] = map_point(i, observed[i].cam, kf);
  DynamicCheck check{DynamicCheckOptions{}};
  std::optional<map::Frame> last;
  for (int frame_id = 1; frame_id <= 3; ++frame_id) {
    for (const size_t i : {0u, 1u, 4u, 6u, 7u, 8u}) observed[i].cam.x() += 0.04;
    map::Frame frame = make_frame(static_cast<uint64_t>(frame_id), observed, points, rng);
    check.inherit(frame, last ? &*last : nullptr);
    const auto stats = check.update(frame, last ? &*last : nullptr);
    if (frame_id == 3) {  // first seen in frame 1, moving in frames 2 and 3: dynamic
      ASSERT_TRUE(frame.dynamic[0]);
      ASSERT_TRUE(frame.dynamic[6]);
      ASSERT_TRUE(frame.dynamic[7]);
      EXPECT_TRUE(frame.dynamic[1]);
      EXPECT_FALSE(frame.dynamic[2]) << "a different depth is another object";
      EXPECT_FALSE(frame.dynamic[3]) << "too far in the image";
      EXPECT_TRUE(frame.dynamic[4]) << "two steps of growth";
      EXPECT_FALSE(frame.dynamic[5]) << "a static match keeps its verdict";
      EXPECT_FALSE(frame.dynamic[8]) << "a lone dynamic keypoint does not grow";
      EXPECT_EQ(stats.grown, 2);
    }
    last = std::move(frame);
  }
}

TEST(DynamicCheck, WithoutDepthTheTwoDofTestApplies) {
  // Monocular: a point moving along the image (no depth) is found too.
  std::mt19937 rng(9);
  auto kf = keyframe(101);
  std::vector<Observed> observed;
  std::vector<std::shared_ptr<map::MapPoint>> points;
  for (size_t i = 0; i < 101; ++i) {
    observed.push_back({random_point(rng), 0});
    points.push_back(map_point(i, observed.back().cam, kf));
  }
  DynamicCheck check{DynamicCheckOptions{}};
  std::optional<map::Frame> last;
  for (int frame_id = 1; frame_id <= 3; ++frame_id) {
    observed[100].cam.y() += 0.05;
    map::Frame frame = make_frame(static_cast<uint64_t>(frame_id), observed, points, rng, false);
    check.inherit(frame, last ? &*last : nullptr);
    check.update(frame, last ? &*last : nullptr);
    last = std::move(frame);
  }
  EXPECT_TRUE(last->dynamic[100]);
  int others = 0;
  for (size_t i = 0; i < 100; ++i) others += last->dynamic[i] ? 1 : 0;
  EXPECT_LE(others, 1);
}

TEST(DynamicCheck, BadOptionsAreInputErrors) {
  DynamicCheckOptions o;
  o.moving_factor = 0;
  EXPECT_THROW(DynamicCheck{o}, InputError);
  o = {};
  o.cull_score = 1;  // below dynamic_score 8
  EXPECT_THROW(DynamicCheck{o}, InputError);
  o = {};
  o.cull_score = 9;  // more verdicts than a map point keeps (8)
  EXPECT_THROW(DynamicCheck{o}, InputError);
  o = {};
  o.certain_factor = 1.0;  // below moving_factor
  EXPECT_THROW(DynamicCheck{o}, InputError);
}
