#include <gtest/gtest.h>

#include <set>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/bow/binary_kmeans.h"
#include "bow_test_data.h"

namespace crowdslam::bow {
namespace {

std::vector<const std::uint8_t*> row_pointers(const cv::Mat& m) {
  std::vector<const std::uint8_t*> rows;
  for (int r = 0; r < m.rows; ++r) rows.push_back(m.ptr<std::uint8_t>(r));
  return rows;
}

TEST(MajorityCentroid, TakesEachBitByMajority) {
  // Three rows: bit 0 set in 2 of 3 -> set; bit 1 set in 1 of 3 -> clear; byte 31 all ones in 3 -> 0xFF.
  cv::Mat m = cv::Mat::zeros(3, 32, CV_8UC1);
  m.at<std::uint8_t>(0, 0) = 0b01;
  m.at<std::uint8_t>(1, 0) = 0b11;
  for (int r = 0; r < 3; ++r) m.at<std::uint8_t>(r, 31) = 0xFF;
  const Descriptor c = majority_centroid(row_pointers(m), {0, 1, 2});
  EXPECT_EQ(c[0], 0b01);
  EXPECT_EQ(c[31], 0xFF);
  for (int b = 1; b < 31; ++b) EXPECT_EQ(c[b], 0);
  // Two rows with one bit each: a tie gives 0.
  EXPECT_EQ(majority_centroid(row_pointers(m), {0, 2})[0], 0);
}

TEST(KMeansBinary, RecoversWellSeparatedClusters) {
  std::mt19937 rng(3);
  std::vector<Descriptor> centres;
  for (int c = 0; c < 6; ++c) centres.push_back(testing::random_descriptor(rng));
  const int per_centre = 40;
  const cv::Mat data = testing::clustered(centres, per_centre, 12, rng);
  std::mt19937_64 kmeans_rng(11);
  const BinaryClusters clusters = kmeans_binary(row_pointers(data), 6, 20, kmeans_rng);
  ASSERT_EQ(clusters.centres.size(), 6u);
  std::set<std::size_t> matched;
  for (std::size_t k = 0; k < clusters.centres.size(); ++k) {
    // Every member of a cluster comes from the same true centre, and the centroid is that centre.
    ASSERT_EQ(clusters.members[k].size(), static_cast<std::size_t>(per_centre));
    const std::size_t truth = clusters.members[k].front() / per_centre;
    for (std::size_t m : clusters.members[k]) EXPECT_EQ(m / per_centre, truth);
    EXPECT_EQ(feature::hamming_distance(clusters.centres[k].data(), centres[truth].data()), 0);
    matched.insert(truth);
  }
  EXPECT_EQ(matched.size(), 6u);
}

TEST(KMeansBinary, FewerDistinctRowsThanKGiveSingletons) {
  std::mt19937 rng(5);
  const Descriptor a = testing::random_descriptor(rng);
  const Descriptor b = testing::random_descriptor(rng);
  const cv::Mat data = testing::to_mat({a, b, a, b, a});
  std::mt19937_64 kmeans_rng(1);
  const BinaryClusters clusters = kmeans_binary(row_pointers(data), 10, 10, kmeans_rng);
  ASSERT_EQ(clusters.centres.size(), 2u);
  std::size_t total = 0;
  for (const auto& m : clusters.members) total += m.size();
  EXPECT_EQ(total, 5u);
}

TEST(KMeansBinary, DeterministicForASeed) {
  std::mt19937 rng(9);
  std::vector<Descriptor> rows;
  for (int i = 0; i < 300; ++i) rows.push_back(testing::random_descriptor(rng));
  const cv::Mat data = testing::to_mat(rows);
  std::mt19937_64 r1(42);
  std::mt19937_64 r2(42);
  const auto c1 = kmeans_binary(row_pointers(data), 8, 10, r1);
  const auto c2 = kmeans_binary(row_pointers(data), 8, 10, r2);
  EXPECT_EQ(c1.centres, c2.centres);
  EXPECT_EQ(c1.members, c2.members);
}

}  // namespace
}  // namespace crowdslam::bow
