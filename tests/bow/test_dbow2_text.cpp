#include <gtest/gtest.h>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::bow {
namespace {

// "b b b ... b" (32 bytes) with byte `at` replaced by `other`.
std::string bytes(int b, int at = -1, int other = 0) {
  std::string out;
  for (int i = 0; i < 32; ++i) out += std::to_string(i == at ? other : b) + (i < 31 ? " " : "");
  return out;
}

// A hand-made two-level DBoW2 tree, k = 2, L = 2:
//   node 1 (all zeros)  -> leaves 3 (byte 0 = 15, weight 0.1), 4 (byte 31 = 240, weight 0.2)
//   node 2 (all 255)    -> leaves 5 (byte 0 = 0, weight 0.3),  6 (byte 31 = 0, weight 0.4)
std::string small_text() {
  return "2 2  0 0\n"
         "0 0 " +
         bytes(0) + " 0\n" + "0 0 " + bytes(255) + " 0\n" + "1 1 " + bytes(0, 0, 15) + " 0.1\n" + "1 1 " +
         bytes(0, 31, 240) + " 0.2\n" + "2 1 " + bytes(255, 0, 0) + " 0.3\n" + "2 1 " + bytes(255, 31, 0) +
         " 0.4\n";
}

cv::Mat descriptor_rows(const std::vector<std::vector<std::uint8_t>>& rows) {
  cv::Mat m(static_cast<int>(rows.size()), 32, CV_8UC1);
  for (int r = 0; r < m.rows; ++r) std::copy(rows[r].begin(), rows[r].end(), m.ptr<std::uint8_t>(r));
  return m;
}

std::vector<std::uint8_t> filled(std::uint8_t b, int at = -1, std::uint8_t other = 0) {
  std::vector<std::uint8_t> d(32, b);
  if (at >= 0) d[at] = other;
  return d;
}

TEST(Dbow2Text, ImportsTreeWordsAndWeights) {
  crowdslam::test::TempDir dir;
  crowdslam::test::write_text(dir / "voc.txt", small_text());
  const Vocabulary voc = Vocabulary::import_dbow2_text((dir / "voc.txt").string());
  EXPECT_EQ(voc.k(), 2);
  EXPECT_EQ(voc.levels(), 2);
  EXPECT_EQ(voc.depth(), 2);
  ASSERT_EQ(voc.num_nodes(), 7u);
  ASSERT_EQ(voc.num_words(), 4u);
  for (WordId w = 0; w < 4; ++w) {
    EXPECT_EQ(voc.word_node(w), w + 3);  // leaves numbered in node order
    EXPECT_FLOAT_EQ(voc.word_weight(w), 0.1f * static_cast<float>(w + 1));
  }
  EXPECT_EQ(voc.parent(4), 1u);
  EXPECT_EQ(voc.parent(5), 2u);
  EXPECT_EQ(voc.node_descriptor(4)[31], 240);

  // Exact leaf descriptors, and slightly perturbed ones, find their words.
  EXPECT_EQ(voc.word_of(filled(0, 0, 15).data()), 0u);
  EXPECT_EQ(voc.word_of(filled(0, 31, 241).data()), 1u);
  EXPECT_EQ(voc.word_of(filled(255, 0, 1).data()), 2u);
  EXPECT_EQ(voc.word_of(filled(255, 31, 0).data()), 3u);

  // TF-IDF: two features in word 0 (0.1 each), one in word 3 (0.4): 0.2 / 0.6 and 0.4 / 0.6.
  const cv::Mat desc = descriptor_rows({filled(0, 0, 15), filled(0, 0, 14), filled(255, 31, 0)});
  BowVector bow;
  FeatureVector features;
  voc.transform(desc, bow, features, 1);
  ASSERT_EQ(bow.size(), 2u);
  EXPECT_NEAR(bow[0], 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(bow[3], 2.0 / 3.0, 1e-6);
  const FeatureVector expected{{1, {0, 1}}, {2, {2}}};
  EXPECT_EQ(features, expected);

  // The imported tree saves to and loads from our binary format unchanged; read() detects both.
  voc.save((dir / "voc.bin").string());
  BowVector reloaded;
  Vocabulary::read((dir / "voc.bin").string()).transform(desc, reloaded);
  EXPECT_EQ(reloaded, bow);
  EXPECT_EQ(Vocabulary::read((dir / "voc.txt").string()).num_words(), 4u);
}

void expect_import_error(const std::string& content, const std::string& expected) {
  crowdslam::test::TempDir dir;
  const std::string path = (dir / "bad.txt").string();
  crowdslam::test::write_text(path, content);
  try {
    Vocabulary::import_dbow2_text(path);
    FAIL() << "imported a bad file, expected: " << expected;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + expected), std::string::npos) << e.what();
  }
}

TEST(Dbow2Text, BadFilesNameFileAndLine) {
  const std::string text = small_text();
  // A 16-byte descriptor on line 3.
  expect_import_error("2 2 0 0\n0 0 " + bytes(0) + " 0\n0 0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 0\n",
                      ":3: expected 35 fields");
  expect_import_error("2 2 1 0\n", ":1: only L1-norm scoring");
  expect_import_error("2 2\n", ":1: expected the DBoW2 header");
  expect_import_error("2 2 0 0\n0 0 " + bytes(0, 5, 300) + " 0\n", ":2: bad descriptor byte '300'");
  expect_import_error("2 2 0 0\n7 1 " + bytes(0) + " 0\n", ":2: bad parent id '7'");
  // Node 1 declared a leaf although nodes 3 and 4 hang below it.
  std::string leaf_with_children = text;
  leaf_with_children.replace(leaf_with_children.find("\n0 0 ") + 1, 4, "0 1 ");
  expect_import_error(leaf_with_children, ":2: node 1 is declared a leaf but has children");
  // Three children under the root with k = 2.
  expect_import_error(text + "0 1 " + bytes(7) + " 0.5\n", ": node 0 has more than k = 2 children");
  expect_import_error("", ": empty vocabulary file");
}

}  // namespace
}  // namespace crowdslam::bow
