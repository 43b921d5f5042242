// Training details: majority centroids over many rows (the counters are packed 8 bits wide and must be
// emptied before they overflow) and the progress reports of Vocabulary::train.
#include <gtest/gtest.h>

#include <random>

#include "bow_test_data.h"
#include "crowdslam/bow/binary_kmeans.h"
#include "crowdslam/bow/vocabulary.h"

namespace crowdslam::bow {
namespace {

TEST(MajorityCentroid, CountsExactlyOverManyRows) {
  // 1000 rows; bit b of byte 0 is set in `ones[b]` of them. Majority means more than 500.
  const int n = 1000;
  const int ones[8] = {0, 255, 256, 500, 501, 511, 512, 1000};
  cv::Mat m = cv::Mat::zeros(n, 32, CV_8UC1);
  for (int bit = 0; bit < 8; ++bit) {
    for (int r = 0; r < ones[bit]; ++r) m.at<std::uint8_t>(r, 0) |= static_cast<std::uint8_t>(1u << bit);
  }
  for (int r = 0; r < 600; ++r) m.at<std::uint8_t>(r, 31) = 0xFF;  // byte 31: 600 of 1000 -> all set
  std::vector<const std::uint8_t*> rows;
  std::vector<std::size_t> members;
  for (int r = 0; r < n; ++r) {
    rows.push_back(m.ptr<std::uint8_t>(r));
    members.push_back(static_cast<std::size_t>(r));
  }
  const Descriptor c = majority_centroid(rows, members);
  EXPECT_EQ(c[0], 0b11110000);  // bits 4..7 have 501, 511, 512, 1000 > 500
  EXPECT_EQ(c[31], 0xFF);
  for (int b = 1; b < 31; ++b) EXPECT_EQ(c[b], 0);
}

TEST(VocabularyTrain, ReportsProgressLevelByLevelUpToAllDescriptors) {
  std::mt19937 rng(6);
  std::vector<Descriptor> rows;
  for (int i = 0; i < 500; ++i) rows.push_back(testing::random_descriptor(rng));
  VocabularyTrainOptions options;
  options.k = 3;
  options.levels = 4;
  std::vector<VocabularyTrainProgress> reports;
  options.progress = [&](const VocabularyTrainProgress& p) { reports.push_back(p); };
  const Vocabulary voc = Vocabulary::train({testing::to_mat(rows)}, options);
  ASSERT_FALSE(reports.empty());
  // One report per clustered node: the inner nodes plus the nodes at level L - 1 that became leaves.
  std::size_t inner = 0;
  for (NodeId node = 0; node < voc.num_nodes(); ++node)
    inner += voc.children_begin(node) != voc.children_end(node);
  EXPECT_GE(reports.size(), inner);
  EXPECT_EQ(reports.front().level, 1);
  EXPECT_EQ(reports.front().descriptors_total, 500u);  // the root holds every descriptor
  int level = 1;
  std::size_t done = 0;
  std::size_t total = reports.front().descriptors_total;
  for (const auto& p : reports) {
    EXPECT_EQ(p.levels, 4);
    if (p.level != level) {
      EXPECT_EQ(p.level, level + 1);  // levels in order, none skipped
      EXPECT_EQ(done, total);         // the previous level was finished
      level = p.level;
      done = 0;
      total = p.descriptors_total;
    }
    EXPECT_EQ(p.descriptors_total, total);
    EXPECT_GT(p.descriptors_done, done);
    EXPECT_LE(p.descriptors_done, p.descriptors_total);
    done = p.descriptors_done;
  }
  EXPECT_EQ(level, 4);
  EXPECT_EQ(reports.back().descriptors_done, reports.back().descriptors_total);
}

}  // namespace
}  // namespace crowdslam::bow
