#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "crowdslam/feature/quadtree.h"

namespace crowdslam::feature {
namespace {

std::vector<cv::KeyPoint> random_keypoints(int count, float width, float height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> x(0, static_cast<int>(width) - 1);
  std::uniform_int_distribution<int> y(0, static_cast<int>(height) - 1);
  std::uniform_real_distribution<float> response(1.f, 100.f);
  std::set<std::pair<int, int>> used;
  std::vector<cv::KeyPoint> keypoints;
  while (static_cast<int>(keypoints.size()) < count) {
    const std::pair<int, int> position(x(rng), y(rng));
    if (!used.insert(position).second) continue;
    keypoints.emplace_back(cv::Point2f(position.first, position.second), 7.f, -1.f, response(rng));
  }
  return keypoints;
}

// 16 wanted in a square: two full rounds of splitting give the 4 x 4 grid of cells, each keeping its
// strongest keypoint.
TEST(Quadtree, KeepsTheStrongestKeypointOfEachCellOfAFourByFourSplit) {
  std::vector<cv::KeyPoint> candidates = random_keypoints(3000, 256, 256, 1);
  std::vector<float> best(16, 0.f);
  for (const cv::KeyPoint& k : candidates) {
    const int cell = static_cast<int>(k.pt.y) / 64 * 4 + static_cast<int>(k.pt.x) / 64;
    best[cell] = std::max(best[cell], k.response);
  }
  QuadtreeDistributor distributor;
  std::vector<cv::KeyPoint> selected;
  distributor.distribute(candidates, cv::Rect2f(0, 0, 256, 256), 16, selected);
  ASSERT_EQ(selected.size(), 16u);
  std::vector<int> per_cell(16, 0);
  for (const cv::KeyPoint& k : selected) {
    const int cell = static_cast<int>(k.pt.y) / 64 * 4 + static_cast<int>(k.pt.x) / 64;
    ++per_cell[cell];
    EXPECT_EQ(k.response, best[cell]) << "cell " << cell;
  }
  EXPECT_EQ(per_cell, std::vector<int>(16, 1));
}

TEST(Quadtree, AnIsolatedWeakKeypointSurvivesNextToAStrongCluster) {
  std::vector<cv::KeyPoint> candidates;
  for (int i = 0; i < 200; ++i) {
    candidates.emplace_back(cv::Point2f(10.f + i % 20, 10.f + i / 20), 7.f, -1.f, 100.f + i);
  }
  candidates.emplace_back(cv::Point2f(600.f, 400.f), 7.f, -1.f, 1.f);
  QuadtreeDistributor distributor;
  std::vector<cv::KeyPoint> selected;
  distributor.distribute(candidates, cv::Rect2f(0, 0, 640, 480), 10, selected);
  EXPECT_EQ(selected.size(), 10u);
  const bool has_isolated = std::any_of(selected.begin(), selected.end(), [](const cv::KeyPoint& k) {
    return k.pt == cv::Point2f(600.f, 400.f);
  });
  EXPECT_TRUE(has_isolated);
}

TEST(Quadtree, ReturnsExactlyTheTargetOrAllCandidates) {
  QuadtreeDistributor distributor;
  for (const int target : {1, 2, 5, 37, 100, 323, 999, 1000, 1500}) {
    std::vector<cv::KeyPoint> candidates = random_keypoints(1000, 600, 440, 7u + target);
    std::vector<cv::KeyPoint> selected;
    distributor.distribute(candidates, cv::Rect2f(0, 0, 600, 440), target, selected);
    EXPECT_EQ(static_cast<int>(selected.size()), std::min(target, 1000)) << "target " << target;
    std::set<std::pair<float, float>> positions;
    for (const cv::KeyPoint& k : selected) positions.insert({k.pt.x, k.pt.y});
    EXPECT_EQ(positions.size(), selected.size()) << "a keypoint was selected twice";
  }
}

TEST(Quadtree, AppendsToTheOutputAndHandlesDegenerateInput) {
  QuadtreeDistributor distributor;
  std::vector<cv::KeyPoint> selected(3);
  std::vector<cv::KeyPoint> none;
  distributor.distribute(none, cv::Rect2f(0, 0, 100, 100), 10, selected);
  EXPECT_EQ(selected.size(), 3u);

  std::vector<cv::KeyPoint> some = random_keypoints(50, 100, 100, 3);
  distributor.distribute(some, cv::Rect2f(0, 0, 100, 100), 0, selected);
  EXPECT_EQ(selected.size(), 3u);

  // Identical positions cannot be separated: splitting stops and the strongest one is kept.
  std::vector<cv::KeyPoint> duplicates;
  for (int i = 0; i < 50; ++i) duplicates.emplace_back(cv::Point2f(42.f, 17.f), 7.f, -1.f, float(i));
  distributor.distribute(duplicates, cv::Rect2f(0, 0, 100, 100), 20, selected);
  ASSERT_EQ(selected.size(), 4u);
  EXPECT_EQ(selected.back().response, 49.f);
}

}  // namespace
}  // namespace crowdslam::feature
