// Frames localised afterwards in a map (tracking/localize_frames.h), on a scene built in closed form:
// random points with random descriptors, a monocular camera stepping along x, and frames in which people
// hide the view (too few keypoints to localise).
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <random>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/tracking/localize_frames.h"
#include "tracking_test_camera.h"

using namespace crowdslam;
using geometry::SE3;
using geometry::Vec3;

namespace {

constexpr double kFrameS = 0.1;  // 10 Hz
constexpr double kStepM = 0.02;  // camera travel per frame along x

struct Scene {
  std::shared_ptr<geometry::PinholeCamera> camera = test::rgbd_test_camera();
  std::shared_ptr<map::ScaleLevels> levels = std::make_shared<map::ScaleLevels>(1.2f, 8);
  std::vector<Vec3> points;
  std::vector<std::array<uint8_t, 32>> descriptors;
  std::vector<std::shared_ptr<map::MapPoint>> map_points;
  std::mt19937 rng{11};

  Scene() {
    camera->bf = 0;  // monocular
    std::uniform_real_distribution<double> ux(-2.5, 2.5), uy(-1.8, 1.8), uz(3.0, 6.0);
    for (int i = 0; i < 600; ++i) {
      points.emplace_back(ux(rng), uy(rng), uz(rng));
      std::array<uint8_t, 32> d;
      for (auto& b : d) b = static_cast<uint8_t>(rng());
      descriptors.push_back(d);
    }
    // The map: every point observed by one keyframe at the pose of frame 10.
    std::vector<int> seen;
    auto kf = std::make_shared<map::KeyFrame>(0, 10, 10 * kFrameS, camera, levels,
                                              observe(pose(10), 1.0, seen), pose(10));
    for (size_t i = 0; i < points.size(); ++i) {
      if (seen[i] < 0) continue;
      auto p = std::make_shared<map::MapPoint>(i, points[i], kf, 10);
      p->add_observation(kf, static_cast<size_t>(seen[i]));
      kf->add_map_point(static_cast<size_t>(seen[i]), p);
      p->compute_distinctive_descriptor();
      p->update_normal_and_depth();
      map_points.push_back(p);
    }
  }

  static SE3 pose(int frame) {  // cam_from_world of frame `frame`
    return SE3(Eigen::Quaterniond::Identity(), Vec3(-kStepM * frame, 0, 0));
  }

  // Keypoints of the points visible from `cam_from_world`, each kept with probability `visible` (the rest
  // hidden by people), at the projection plus 0.3 px noise.
  std::shared_ptr<map::FrameFeatures> observe(const SE3& cam_from_world, double visible,
                                              std::vector<int>& seen) {
    auto f = std::make_shared<map::FrameFeatures>();
    std::normal_distribution<float> noise(0.0f, 0.3f);
    std::uniform_real_distribution<double> keep(0.0, 1.0);
    std::vector<std::array<uint8_t, 32>> desc;
    seen.assign(points.size(), -1);
    for (size_t i = 0; i < points.size(); ++i) {
      const Vec3 c = cam_from_world * points[i];
      const auto px = camera->project(c);
      if (c.z() <= 0.1 || px.x() < 0 || px.x() >= 640 || px.y() < 0 || px.y() >= 480) continue;
      if (keep(rng) >= visible) continue;
      seen[i] = static_cast<int>(f->keys.size());
      f->keys.emplace_back(
          cv::Point2f(static_cast<float>(px.x()) + noise(rng), static_cast<float>(px.y()) + noise(rng)), 31,
          45.0f, 1, 0);
      f->depth_m.push_back(-1);
      f->right_u.push_back(-1);
      desc.push_back(descriptors[i]);
    }
    f->keys_un = f->keys;
    f->descriptors = cv::Mat(static_cast<int>(desc.size()), 32, CV_8UC1);
    for (size_t i = 0; i < desc.size(); ++i)
      std::memcpy(f->descriptors.ptr(static_cast<int>(i)), desc[i].data(), 32);
    f->grid = map::FeatureGrid(f->keys_un, camera->undistorted_bounds());
    return f;
  }

  // Frames 0..9, oldest first; those in `hidden` keep 3 % of their points (about 10 keypoints).
  std::deque<map::Frame> frames(const std::vector<int>& hidden) {
    std::deque<map::Frame> out;
    for (int k = 0; k < 10; ++k) {
      const bool is_hidden = std::find(hidden.begin(), hidden.end(), k) != hidden.end();
      std::vector<int> seen;
      out.emplace_back(static_cast<uint64_t>(k), k * kFrameS, camera, levels,
                       observe(pose(k), is_hidden ? 0.03 : 1.0, seen));
    }
    return out;
  }
};

// The largest camera-centre error of `recovered` against the truth, and the frame ids recovered.
double worst_error(const tracking::FramePoses& recovered, std::vector<uint64_t>& ids) {
  double worst = 0;
  for (const auto& [id, p] : recovered) {
    ids.push_back(id);
    const Vec3 centre = p.inverse().translation();
    const Vec3 truth = Scene::pose(static_cast<int>(id)).inverse().translation();
    worst = std::max(worst, (centre - truth).norm());
  }
  std::sort(ids.begin(), ids.end());
  return worst;
}

}  // namespace

TEST(LocalizeBackwards, StopsAtTheFirstFrameThatFailsWithoutAGap) {
  Scene s;
  auto frames = s.frames({5});
  SE3 later = Scene::pose(10);
  SE3 step = Scene::pose(9) * Scene::pose(10).inverse();
  const auto recovered = tracking::localize_backwards(frames, later, step, s.map_points, {});
  std::vector<uint64_t> ids;
  EXPECT_LT(worst_error(recovered, ids), 0.005);
  EXPECT_EQ(ids, (std::vector<uint64_t>{6, 7, 8, 9}));
  ASSERT_EQ(frames.size(), 6u);  // 0..5 left, oldest first
  EXPECT_EQ(frames.front().id, 0u);
  EXPECT_EQ(frames.back().id, 5u);
  EXPECT_NEAR((later.inverse().translation() - Scene::pose(6).inverse().translation()).norm(), 0, 0.005);
}

TEST(LocalizeBackwards, SkipsHiddenFramesWithinTheGapAndGoesOnByTheSameStep) {
  Scene s;
  auto frames = s.frames({4, 5, 6});
  SE3 later = Scene::pose(10);
  SE3 step = Scene::pose(9) * Scene::pose(10).inverse();
  // Three hidden frames (0.3 s): within a gap of 0.35 s the frames before them are localised.
  const auto recovered = tracking::localize_backwards(frames, later, step, s.map_points, {}, 0.35);
  std::vector<uint64_t> ids;
  EXPECT_LT(worst_error(recovered, ids), 0.005);
  EXPECT_EQ(ids, (std::vector<uint64_t>{0, 1, 2, 3, 7, 8, 9}));
  // The skipped frames are left, oldest first; `later` is the oldest frame localised.
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames.front().id, 4u);
  EXPECT_EQ(frames.back().id, 6u);
  EXPECT_NEAR((later.inverse().translation() - Scene::pose(0).inverse().translation()).norm(), 0, 0.005);
}

TEST(LocalizeBackwards, StopsWhereTheGapIsLongerThanAllowed) {
  Scene s;
  auto frames = s.frames({2, 3, 4, 5, 6});
  SE3 later = Scene::pose(10);
  SE3 step = Scene::pose(9) * Scene::pose(10).inverse();
  // Five hidden frames (0.5 s) against a gap of 0.35 s: frames 0 and 1 are not reached.
  const auto recovered = tracking::localize_backwards(frames, later, step, s.map_points, {}, 0.35);
  std::vector<uint64_t> ids;
  EXPECT_LT(worst_error(recovered, ids), 0.005);
  EXPECT_EQ(ids, (std::vector<uint64_t>{7, 8, 9}));
  EXPECT_EQ(frames.size(), 7u);  // 0..6
}
