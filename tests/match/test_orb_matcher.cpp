#include <gtest/gtest.h>

#include <random>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"
#include "crowdslam/match/orb_matcher.h"
#include "crowdslam/match/rotation_histogram.h"

using namespace crowdslam;
using namespace crowdslam::map;
using geometry::SE3;
using geometry::Vec3;

namespace {

// A scene of random 3D points with random descriptors, observed from several poses. Keypoints are the
// exact projections plus small noise, with descriptors equal to the point's up to a few flipped bits,
// and extra distractor keypoints with random descriptors.
struct Scene {
  std::shared_ptr<geometry::PinholeCamera> camera = std::make_shared<geometry::PinholeCamera>();
  std::shared_ptr<ScaleLevels> levels = std::make_shared<ScaleLevels>(1.2f, 8);
  std::vector<Vec3> points;
  std::vector<std::array<uint8_t, 32>> descriptors;
  std::mt19937 rng{5};
  Map map;

  Scene() {
    camera->fx = camera->fy = 500;
    camera->cx = 320;
    camera->cy = 240;
    camera->width = 640;
    camera->height = 480;
    camera->bf = 40;
    std::uniform_real_distribution<double> ux(-2.0, 2.0), uy(-1.5, 1.5), uz(3.0, 6.0);
    for (int i = 0; i < 400; ++i) {
      points.emplace_back(ux(rng), uy(rng), uz(rng));
      std::array<uint8_t, 32> d;
      for (auto& b : d) b = static_cast<uint8_t>(rng());
      descriptors.push_back(d);
    }
  }

  // Features seen from cam_from_world; truth[i] = keypoint index of point i (or -1).
  std::shared_ptr<FrameFeatures> observe(const SE3& cam_from_world, std::vector<int>& truth, int distractors = 200,
                                         bool with_depth = true) {
    auto f = std::make_shared<FrameFeatures>();
    std::normal_distribution<float> noise(0.0f, 0.3f);
    std::uniform_int_distribution<int> bit(0, 255);
    std::vector<std::array<uint8_t, 32>> desc;
    truth.assign(points.size(), -1);
    for (size_t i = 0; i < points.size(); ++i) {
      const Vec3 c = cam_from_world * points[i];
      if (c.z() <= 0.1) continue;
      const auto px = camera->project(c);
      if (px.x() < 0 || px.x() >= 640 || px.y() < 0 || px.y() >= 480) continue;
      cv::KeyPoint kp(cv::Point2f(static_cast<float>(px.x()) + noise(rng), static_cast<float>(px.y()) + noise(rng)),
                      31, 45.0f, 1, 0);
      truth[i] = static_cast<int>(f->keys.size());
      f->keys.push_back(kp);
      f->depth_m.push_back(with_depth ? static_cast<float>(c.z()) : -1.0f);
      f->right_u.push_back(with_depth ? static_cast<float>(kp.pt.x - camera->bf / c.z()) : -1.0f);
      auto d = descriptors[i];
      for (int k = 0; k < 3; ++k) {
        const int b = bit(rng);
        d[static_cast<size_t>(b / 8)] ^= static_cast<uint8_t>(1u << (b % 8));
      }
      desc.push_back(d);
    }
    std::uniform_real_distribution<float> ux(0, 640), uy(0, 480);
    for (int k = 0; k < distractors; ++k) {
      f->keys.emplace_back(cv::Point2f(ux(rng), uy(rng)), 31, 45.0f, 1, 0);
      f->depth_m.push_back(-1);
      f->right_u.push_back(-1);
      std::array<uint8_t, 32> d;
      for (auto& b : d) b = static_cast<uint8_t>(rng());
      desc.push_back(d);
    }
    f->keys_un = f->keys;
    f->descriptors = cv::Mat(static_cast<int>(desc.size()), 32, CV_8UC1);
    for (size_t i = 0; i < desc.size(); ++i) std::memcpy(f->descriptors.ptr(static_cast<int>(i)), desc[i].data(), 32);
    f->grid = FeatureGrid(f->keys_un, camera->undistorted_bounds());
    return f;
  }

  // A keyframe at `pose` with map points for every visible scene point. points_out[i] = map point of point i.
  std::shared_ptr<KeyFrame> keyframe_with_points(const SE3& pose, std::vector<std::shared_ptr<MapPoint>>& points_out,
                                                 std::vector<int>& truth) {
    auto kf = std::make_shared<KeyFrame>(map.next_keyframe_id(), 0, 0.0, camera, levels, observe(pose, truth), pose);
    map.add_keyframe(kf);
    points_out.assign(points.size(), nullptr);
    for (size_t i = 0; i < points.size(); ++i) {
      if (truth[i] < 0) continue;
      auto p = std::make_shared<MapPoint>(map.next_map_point_id(), points[i], kf, 0);
      p->add_observation(kf, static_cast<size_t>(truth[i]));
      kf->add_map_point(static_cast<size_t>(truth[i]), p);
      p->compute_distinctive_descriptor();
      p->update_normal_and_depth();
      points_out[i] = p;
      map.add_map_point(p);
    }
    return kf;
  }
};

SE3 small_motion(double tx, double yaw_deg) {
  geometry::Vec6 twist = geometry::Vec6::Zero();
  twist(0) = tx;
  twist(4) = yaw_deg * M_PI / 180.0;
  return SE3::exp(twist);
}

}  // namespace

TEST(RotationHistogram, RejectsMatchesOutsideDominantBins) {
  match::RotationHistogram h;
  for (size_t i = 0; i < 50; ++i) h.add(10.0f, i);          // dominant
  for (size_t i = 50; i < 60; ++i) h.add(-350.0f, i);       // same angle modulo 360
  for (size_t i = 60; i < 63; ++i) h.add(180.0f, i);        // < 10% of dominant: rejected
  const auto rejected = h.rejected();
  EXPECT_EQ(rejected.size(), 3u);
  for (size_t id : rejected) EXPECT_GE(id, 60u);
}

TEST(OrbMatcher, SearchFromLastFrameFindsTrueMatches) {
  Scene s;
  const SE3 pose0 = SE3::identity();
  std::vector<int> truth0, truth1;
  Frame last(0, 0.0, s.camera, s.levels, s.observe(pose0, truth0));
  last.cam_from_world = pose0;
  std::vector<std::shared_ptr<MapPoint>> mps(s.points.size());
  auto kf = std::make_shared<KeyFrame>(0, 0, 0.0, s.camera, s.levels, last.features, pose0);
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (truth0[i] < 0) continue;
    mps[i] = std::make_shared<MapPoint>(i, s.points[i], kf, 0);
    mps[i]->add_observation(kf, static_cast<size_t>(truth0[i]));
    kf->add_map_point(static_cast<size_t>(truth0[i]), mps[i]);
    mps[i]->compute_distinctive_descriptor();
    mps[i]->update_normal_and_depth();
    last.map_points[static_cast<size_t>(truth0[i])] = mps[i];
  }
  const SE3 pose1 = small_motion(0.05, 2.0) * pose0;
  Frame current(1, 0.033, s.camera, s.levels, s.observe(pose1, truth1));
  current.cam_from_world = pose1;  // exact guess
  const int n = match::search_from_last_frame(current, last, 7.0);
  int correct = 0, visible_both = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (truth0[i] < 0 || truth1[i] < 0) continue;
    ++visible_both;
    if (current.map_points[static_cast<size_t>(truth1[i])] == mps[i]) ++correct;
  }
  EXPECT_EQ(n, std::count_if(current.map_points.begin(), current.map_points.end(), [](auto& p) { return p != nullptr; }));
  EXPECT_GT(correct, 0.95 * visible_both);
  EXPECT_LE(n - correct, 2);  // almost no wrong matches

  // With a pose guess 40 px off, a window of 7 px finds (almost) nothing: the search is really local.
  Frame off(2, 0.066, s.camera, s.levels, current.features);
  off.cam_from_world = small_motion(0.4, 0.0) * pose1;
  EXPECT_LT(match::search_from_last_frame(off, last, 7.0), 0.1 * visible_both);
}

TEST(OrbMatcher, SearchLocalPointsUsesProjections) {
  Scene s;
  std::vector<std::shared_ptr<MapPoint>> mps;
  std::vector<int> truth0, truth1;
  s.keyframe_with_points(SE3::identity(), mps, truth0);
  const SE3 pose1 = small_motion(0.1, -3.0);
  Frame frame(1, 0.1, s.camera, s.levels, s.observe(pose1, truth1));
  frame.cam_from_world = pose1;
  std::vector<match::ProjectedPoint> projected;
  for (const auto& p : mps) {
    if (!p) continue;
    if (auto proj = frame.project(*p)) projected.push_back({p, *proj});
  }
  ASSERT_GT(projected.size(), 100u);
  const int n = match::search_local_points(frame, projected);
  int correct = 0, visible_both = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (truth0[i] < 0 || truth1[i] < 0) continue;
    ++visible_both;
    if (frame.map_points[static_cast<size_t>(truth1[i])] == mps[i]) ++correct;
  }
  EXPECT_GT(correct, 0.9 * visible_both);
  EXPECT_LE(n - correct, 3);
}

TEST(OrbMatcher, KeyframeWindowSearchWithoutPose) {
  Scene s;
  std::vector<std::shared_ptr<MapPoint>> mps;
  std::vector<int> truth0, truth1;
  auto kf = s.keyframe_with_points(SE3::identity(), mps, truth0);
  const SE3 pose1 = small_motion(0.03, 1.0);  // a few pixels of image motion
  Frame frame(1, 0.1, s.camera, s.levels, s.observe(pose1, truth1));
  const int n = match::search_keyframe_window(frame, *kf, 30.0);
  int correct = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (truth0[i] >= 0 && truth1[i] >= 0 && frame.map_points[static_cast<size_t>(truth1[i])] == mps[i]) ++correct;
  }
  EXPECT_GT(correct, 200);
  EXPECT_LE(n - correct, 3);
}

TEST(OrbMatcher, TriangulationSearchRespectsEpipolarGeometry) {
  Scene s;
  std::vector<int> truth1, truth2;
  const SE3 pose1 = SE3::identity();
  const SE3 pose2 = small_motion(0.3, 3.0);
  auto kf1 = std::make_shared<KeyFrame>(0, 0, 0.0, s.camera, s.levels, s.observe(pose1, truth1, 0, false), pose1);
  auto kf2 = std::make_shared<KeyFrame>(1, 1, 0.1, s.camera, s.levels, s.observe(pose2, truth2, 0, false), pose2);
  const auto f21 = match::fundamental_between(*kf1, *kf2);
  // F is consistent with the geometry: x2^T F x1 ~ 0 for true correspondences (noise-free check).
  const Vec3 x1(s.camera->project(pose1 * s.points[0]).x(), s.camera->project(pose1 * s.points[0]).y(), 1);
  const Vec3 x2(s.camera->project(pose2 * s.points[0]).x(), s.camera->project(pose2 * s.points[0]).y(), 1);
  EXPECT_NEAR(x2.dot(f21 * x1) / (f21 * x1).head<2>().norm(), 0.0, 1e-6);

  const auto matches = match::search_for_triangulation(*kf1, *kf2, f21, false, true);
  int correct = 0;
  for (const auto& [i1, i2] : matches) {
    for (size_t p = 0; p < s.points.size(); ++p) {
      if (truth1[p] == static_cast<int>(i1) && truth2[p] == static_cast<int>(i2)) ++correct;
    }
  }
  EXPECT_GT(correct, 250);
  EXPECT_GE(correct, static_cast<int>(matches.size()) - 2);

  // A keypoint with an identical descriptor but off the epipolar line is not matched.
  auto f2 = std::const_pointer_cast<FrameFeatures>(kf2->features);
  const size_t i1 = static_cast<size_t>(truth1[0]);
  const size_t i2 = static_cast<size_t>(truth2[0]);
  f2->keys_un[i2].pt.y += 40.0f;
  f2->grid = FeatureGrid(f2->keys_un, s.camera->undistorted_bounds());
  const auto again = match::search_for_triangulation(*kf1, *kf2, f21, false, true);
  for (const auto& [a, b] : again) EXPECT_FALSE(a == i1 && b == i2);
}

TEST(OrbMatcher, FuseMergesDuplicatePoints) {
  Scene s;
  std::vector<std::shared_ptr<MapPoint>> mps1, mps2;
  std::vector<int> t1, t2;
  auto kf1 = s.keyframe_with_points(SE3::identity(), mps1, t1);
  auto kf2 = s.keyframe_with_points(small_motion(0.05, 1.0), mps2, t2);
  // Fuse kf1's points into kf2: points seen by both get merged.
  std::vector<std::shared_ptr<MapPoint>> to_fuse;
  for (auto& p : mps1) {
    if (p) to_fuse.push_back(p);
  }
  const int fused = match::fuse(kf2, to_fuse);
  int both = 0, merged = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (t1[i] < 0 || t2[i] < 0) continue;
    ++both;
    auto a = kf1->map_point(static_cast<size_t>(t1[i]));
    auto b = kf2->map_point(static_cast<size_t>(t2[i]));
    if (a && a == b) ++merged;
  }
  EXPECT_GT(merged, 0.9 * both);
  EXPECT_GE(fused, merged);
}
