// The triangulation search guided by the vocabulary's direct index (ORB-SLAM2's SearchForTriangulation)
// against the exhaustive search on a scene with known correspondences: random 3D points with random
// descriptors seen from two poses (3 bits of noise per descriptor), plus distractors. The vocabulary is
// trained on the scene's own descriptors, as a real vocabulary is trained on descriptors like the ones
// it will see.
//
// Tolerance: the guided search may miss a correspondence whose two noisy descriptors fall under
// different nodes, so it must find at least 90 % of the true pairs the exhaustive search finds; it
// compares fewer pairs, so it may not find any wrong pair the exhaustive search does not (both <= 2).
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <random>
#include <set>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/match/orb_matcher.h"

using namespace crowdslam;
using namespace crowdslam::map;
using geometry::SE3;
using geometry::Vec3;

namespace {

struct TwoViews {
  std::shared_ptr<geometry::PinholeCamera> camera = std::make_shared<geometry::PinholeCamera>();
  std::shared_ptr<ScaleLevels> levels = std::make_shared<ScaleLevels>(1.2f, 8);
  std::vector<Vec3> points;
  std::vector<std::array<uint8_t, 32>> descriptors;
  std::mt19937 rng{11};

  TwoViews() {
    camera->fx = camera->fy = 500;
    camera->cx = 320;
    camera->cy = 240;
    camera->width = 640;
    camera->height = 480;
    std::uniform_real_distribution<double> ux(-3.0, 3.0), uy(-2.0, 2.0), uz(4.0, 10.0);
    for (int i = 0; i < 1500; ++i) {
      points.emplace_back(ux(rng), uy(rng), uz(rng));
      std::array<uint8_t, 32> d;
      for (auto& b : d) b = static_cast<uint8_t>(rng());
      descriptors.push_back(d);
    }
  }

  // Monocular features seen from `pose` (truth[i] = keypoint of point i or -1) and 300 distractors.
  std::shared_ptr<FrameFeatures> observe(const SE3& pose, std::vector<int>& truth) {
    auto f = std::make_shared<FrameFeatures>();
    std::normal_distribution<float> noise(0.0f, 0.3f);
    std::uniform_int_distribution<int> bit(0, 255);
    std::vector<std::array<uint8_t, 32>> desc;
    truth.assign(points.size(), -1);
    const auto add = [&](cv::Point2f pt, std::array<uint8_t, 32> d) {
      f->keys.emplace_back(pt, 31, 45.0f, 1, 0);
      f->depth_m.push_back(-1);
      f->right_u.push_back(-1);
      desc.push_back(d);
    };
    for (size_t i = 0; i < points.size(); ++i) {
      const Vec3 c = pose * points[i];
      if (c.z() <= 0.1) continue;
      const auto px = camera->project(c);
      if (px.x() < 0 || px.x() >= 640 || px.y() < 0 || px.y() >= 480) continue;
      auto d = descriptors[i];
      for (int k = 0; k < 3; ++k) {
        const int b = bit(rng);
        d[static_cast<size_t>(b / 8)] ^= static_cast<uint8_t>(1u << (b % 8));
      }
      truth[i] = static_cast<int>(f->keys.size());
      add(cv::Point2f(static_cast<float>(px.x()) + noise(rng), static_cast<float>(px.y()) + noise(rng)), d);
    }
    std::uniform_real_distribution<float> ux(0, 640), uy(0, 480);
    for (int k = 0; k < 300; ++k) {
      std::array<uint8_t, 32> d;
      for (auto& b : d) b = static_cast<uint8_t>(rng());
      add(cv::Point2f(ux(rng), uy(rng)), d);
    }
    f->keys_un = f->keys;
    f->descriptors = cv::Mat(static_cast<int>(desc.size()), 32, CV_8UC1);
    for (size_t i = 0; i < desc.size(); ++i) std::memcpy(f->descriptors.ptr(static_cast<int>(i)), desc[i].data(), 32);
    f->grid = FeatureGrid(f->keys_un, camera->undistorted_bounds());
    return f;
  }
};

std::shared_ptr<FrameFeatures> with_bow(const FrameFeatures& f, const bow::Vocabulary& vocabulary) {
  auto copy = std::make_shared<FrameFeatures>(f);
  vocabulary.transform(copy->descriptors, copy->bow, copy->bow_features);
  return copy;
}

// (true pairs, wrong pairs) of a search result.
std::pair<int, int> score(const std::vector<std::pair<size_t, size_t>>& matches, const std::vector<int>& truth1,
                          const std::vector<int>& truth2) {
  std::set<std::pair<size_t, size_t>> correct;
  for (size_t p = 0; p < truth1.size(); ++p) {
    if (truth1[p] >= 0 && truth2[p] >= 0) correct.emplace(truth1[p], truth2[p]);
  }
  int right = 0;
  for (const auto& m : matches) right += correct.count(m) > 0 ? 1 : 0;
  return {right, static_cast<int>(matches.size()) - right};
}

}  // namespace

TEST(TriangulationSearch, VocabularyGuidedFindsWhatTheExhaustiveSearchFinds) {
  TwoViews s;
  std::vector<int> truth1, truth2;
  geometry::Vec6 twist = geometry::Vec6::Zero();
  twist(0) = 0.4;                   // sideways
  twist(2) = 0.6;                   // forward, as a car
  twist(4) = 4.0 * M_PI / 180.0;    // yaw
  const SE3 pose1 = SE3::identity();
  const SE3 pose2 = SE3::exp(twist);
  const auto f1 = s.observe(pose1, truth1);
  const auto f2 = s.observe(pose2, truth2);

  cv::Mat training(static_cast<int>(s.descriptors.size()), 32, CV_8UC1);
  for (size_t i = 0; i < s.descriptors.size(); ++i) {
    std::memcpy(training.ptr(static_cast<int>(i)), s.descriptors[i].data(), 32);
  }
  bow::VocabularyTrainOptions options;
  options.k = 10;
  options.levels = 5;  // direct index 3 levels up: level 2, 100 nodes (as the default vocabulary)
  const bow::Vocabulary vocabulary = bow::Vocabulary::train({training}, options);

  const auto plain1 = std::make_shared<KeyFrame>(0, 0, 0.0, s.camera, s.levels, f1, pose1);
  const auto plain2 = std::make_shared<KeyFrame>(1, 1, 0.1, s.camera, s.levels, f2, pose2);
  const auto bow1 = std::make_shared<KeyFrame>(2, 0, 0.0, s.camera, s.levels, with_bow(*f1, vocabulary), pose1);
  const auto bow2 = std::make_shared<KeyFrame>(3, 1, 0.1, s.camera, s.levels, with_bow(*f2, vocabulary), pose2);
  ASSERT_FALSE(bow1->features->bow_features.empty());
  const auto f21 = match::fundamental_between(*plain1, *plain2);

  const auto exhaustive = score(match::search_for_triangulation(*plain1, *plain2, f21, false, true), truth1, truth2);
  const auto guided = score(match::search_for_triangulation(*bow1, *bow2, f21, false, true), truth1, truth2);
  ASSERT_GT(exhaustive.first, 600);  // the scene has that many visible true pairs
  EXPECT_GE(guided.first, static_cast<int>(0.9 * exhaustive.first)) << guided.first << " of " << exhaustive.first;
  EXPECT_LE(guided.second, 2);
  EXPECT_LE(exhaustive.second, 2);
  std::printf("[ measured ] true pairs: exhaustive %d (wrong %d), guided %d (wrong %d)\n", exhaustive.first,
              exhaustive.second, guided.first, guided.second);
}
