#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/util/error.h"
#include "bow_test_data.h"
#include "test_support.h"

namespace crowdslam::bow {
namespace {

using testing::clustered;
using testing::noisy_copy;
using testing::random_descriptor;
using testing::to_mat;

TEST(VocabularyTrain, EachWellSeparatedClusterIsOneWord) {
  std::mt19937 rng(21);
  std::vector<Descriptor> centres;
  for (int c = 0; c < 5; ++c) centres.push_back(random_descriptor(rng));
  const int per_centre = 30;
  const cv::Mat data = clustered(centres, per_centre, 10, rng);
  VocabularyTrainOptions options;
  options.k = 5;
  options.levels = 1;
  const Vocabulary voc = Vocabulary::train({data}, options);
  ASSERT_EQ(voc.num_words(), 5u);
  EXPECT_EQ(voc.depth(), 1);
  std::set<WordId> words;
  for (int c = 0; c < 5; ++c) {
    const WordId word = voc.word_of(data.ptr<std::uint8_t>(c * per_centre));
    for (int i = 0; i < per_centre; ++i)
      EXPECT_EQ(voc.word_of(data.ptr<std::uint8_t>(c * per_centre + i)), word);
    EXPECT_EQ(feature::hamming_distance(voc.node_descriptor(voc.word_node(word)), centres[c].data()), 0);
    words.insert(word);
  }
  EXPECT_EQ(words.size(), 5u);
}

TEST(VocabularyTrain, IdfWeightsAndTfIdfBowFollowTheDefinition) {
  std::mt19937 rng(4);
  const Descriptor a = random_descriptor(rng);
  const Descriptor b = random_descriptor(rng);
  auto copies = [&](const Descriptor& d, int n) {
    std::vector<Descriptor> rows;
    for (int i = 0; i < n; ++i) rows.push_back(noisy_copy(d, 8, rng));
    return rows;
  };
  auto join = [](std::vector<Descriptor> x, const std::vector<Descriptor>& y) {
    x.insert(x.end(), y.begin(), y.end());
    return x;
  };
  // Word A appears in images 0, 2, 3; word B in images 1, 2.
  const std::vector<cv::Mat> images = {to_mat(copies(a, 10)), to_mat(copies(b, 10)),
                                       to_mat(join(copies(a, 5), copies(b, 5))), to_mat(copies(a, 10)),
                                       cv::Mat()};  // an empty image does not count
  VocabularyTrainOptions options;
  options.k = 2;
  options.levels = 1;
  const Vocabulary voc = Vocabulary::train(images, options);
  ASSERT_EQ(voc.num_words(), 2u);
  const WordId word_a = voc.word_of(a.data());
  const WordId word_b = voc.word_of(b.data());
  ASSERT_NE(word_a, word_b);
  EXPECT_NEAR(voc.word_weight(word_a), std::log(4.0 / 3.0), 1e-6);
  EXPECT_NEAR(voc.word_weight(word_b), std::log(4.0 / 2.0), 1e-6);

  BowVector bow;
  voc.transform(to_mat(join(copies(a, 3), copies(b, 1))), bow);
  const double wa = 3 * std::log(4.0 / 3.0);
  const double wb = std::log(2.0);
  ASSERT_EQ(bow.size(), 2u);
  EXPECT_NEAR(bow[word_a], wa / (wa + wb), 1e-6);
  EXPECT_NEAR(bow[word_b], wb / (wa + wb), 1e-6);
}

TEST(VocabularyTrain, DeterministicForASeed) {
  std::mt19937 rng(8);
  std::vector<Descriptor> rows;
  for (int i = 0; i < 400; ++i) rows.push_back(random_descriptor(rng));
  const cv::Mat data = to_mat(rows);
  VocabularyTrainOptions options;
  options.k = 4;
  options.levels = 3;
  crowdslam::test::TempDir dir;
  Vocabulary::train({data}, options).save((dir / "a.voc").string());
  Vocabulary::train({data}, options).save((dir / "b.voc").string());
  EXPECT_EQ(crowdslam::test::read_text(dir / "a.voc"), crowdslam::test::read_text(dir / "b.voc"));
}

TEST(VocabularyTrain, BadOptionsAndInputAreRefused) {
  VocabularyTrainOptions options;
  options.k = 1;
  try {
    options.check();
    FAIL() << "k = 1 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("k must be"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Vocabulary::train({cv::Mat()}, {}), InputError);
  EXPECT_THROW(Vocabulary::train({cv::Mat::zeros(4, 16, CV_8UC1)}, {}), InputError);
}

// Two top clusters, each with three sub-clusters (a two-level tree; the test trains k = 2).
struct TwoLevelData {
  cv::Mat data;
  std::vector<int> top_of_row;
};

TwoLevelData two_level_data(std::mt19937& rng) {
  TwoLevelData out;
  std::vector<Descriptor> rows;
  for (int top = 0; top < 2; ++top) {
    const Descriptor centre = random_descriptor(rng);
    for (int sub = 0; sub < 3; ++sub) {
      const Descriptor sub_centre = noisy_copy(centre, 40, rng);
      for (int i = 0; i < 15; ++i) {
        rows.push_back(noisy_copy(sub_centre, 4, rng));
        out.top_of_row.push_back(top);
      }
    }
  }
  out.data = to_mat(rows);
  return out;
}

TEST(VocabularyDirectIndex, LevelIsNeverDeeperThanTheTree) {
  std::mt19937 rng(13);
  const TwoLevelData d = two_level_data(rng);
  VocabularyTrainOptions options;
  options.k = 2;
  options.levels = 2;
  const Vocabulary voc = Vocabulary::train({d.data}, options);
  ASSERT_EQ(voc.depth(), 2);
  EXPECT_EQ(voc.direct_index_level(kDefaultLevelsUp), 0);
  EXPECT_EQ(voc.direct_index_level(1), 1);
  EXPECT_EQ(voc.direct_index_level(0), 2);
  EXPECT_EQ(voc.direct_index_level(-3), 2);

  BowVector bow;
  FeatureVector features;
  voc.transform(d.data, bow, features);  // default levels_up = 4 on a 2-level tree: the root
  ASSERT_EQ(features.size(), 1u);
  EXPECT_EQ(features.begin()->first, 0u);
  EXPECT_EQ(features.begin()->second.size(), static_cast<std::size_t>(d.data.rows));

  voc.transform(d.data, bow, features, 1);
  ASSERT_EQ(features.size(), 2u);
  std::vector<int> seen(d.data.rows, 0);
  for (const auto& [node, rows] : features) {
    EXPECT_EQ(voc.node_level(node), 1);
    for (unsigned r : rows) {
      ++seen[r];
      EXPECT_EQ(d.top_of_row[r], d.top_of_row[rows.front()]);  // one node per top cluster
    }
  }
  for (int count : seen) EXPECT_EQ(count, 1);
}

class VocabularyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937 rng(17);
    std::vector<cv::Mat> images;
    for (int i = 0; i < 4; ++i) {
      std::vector<Descriptor> rows;
      for (int j = 0; j < 150; ++j) rows.push_back(random_descriptor(rng));
      images.push_back(to_mat(rows));
    }
    VocabularyTrainOptions options;
    options.k = 4;
    options.levels = 3;
    voc_ = Vocabulary::train(images, options);
    std::vector<Descriptor> probe;
    for (int j = 0; j < 200; ++j) probe.push_back(random_descriptor(rng));
    probe_ = to_mat(probe);
    path_ = (dir_ / "small.voc").string();
    voc_.save(path_);
  }

  void expect_load_error(const std::string& content, const std::string& expected) {
    crowdslam::test::write_text(dir_ / "bad.voc", content);
    const std::string bad = (dir_ / "bad.voc").string();
    try {
      Vocabulary::load(bad);
      FAIL() << "loaded a bad file, expected: " << expected;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(bad), std::string::npos) << message;
      EXPECT_NE(message.find(expected), std::string::npos) << message;
    }
  }

  crowdslam::test::TempDir dir_;
  Vocabulary voc_;
  cv::Mat probe_;
  std::string path_;
};

TEST_F(VocabularyFile, RoundTripGivesIdenticalTransforms) {
  const Vocabulary loaded = Vocabulary::load(path_);
  ASSERT_EQ(loaded.num_nodes(), voc_.num_nodes());
  ASSERT_EQ(loaded.num_words(), voc_.num_words());
  EXPECT_EQ(loaded.k(), 4);
  EXPECT_EQ(loaded.levels(), 3);
  EXPECT_EQ(loaded.depth(), voc_.depth());
  BowVector bow_a;
  BowVector bow_b;
  FeatureVector feat_a;
  FeatureVector feat_b;
  voc_.transform(probe_, bow_a, feat_a, 1);
  loaded.transform(probe_, bow_b, feat_b, 1);
  EXPECT_FALSE(bow_a.empty());
  EXPECT_EQ(bow_a, bow_b);
  EXPECT_EQ(feat_a, feat_b);
  EXPECT_EQ(Vocabulary::read(path_).num_words(), voc_.num_words());
}

TEST_F(VocabularyFile, MissingFileIsAnError) {
  EXPECT_THROW(Vocabulary::load((dir_ / "none.voc").string()), InputError);
}

TEST_F(VocabularyFile, WrongMagicIsAnError) {
  expect_load_error("this is not a vocabulary file at all, no", "wrong magic");
}

TEST_F(VocabularyFile, TruncatedFileIsAnError) {
  const std::string content = crowdslam::test::read_text(path_);
  expect_load_error(content.substr(0, content.size() - 10), "truncated");
  expect_load_error(content.substr(0, 20), "truncated");
}

TEST_F(VocabularyFile, WrongDescriptorLengthIsAnError) {
  std::string content = crowdslam::test::read_text(path_);
  content[12] = 64;  // descriptor bytes field of the header
  expect_load_error(content, "64 bytes");
}

TEST_F(VocabularyFile, InconsistentTreeIsAnError) {
  std::string content = crowdslam::test::read_text(path_);
  // Node 1's parent (first field of its record, after the 32-byte header and the root's 44 bytes) -> 5.
  content[32 + 44] = 5;
  expect_load_error(content, "parent");
}

}  // namespace
}  // namespace crowdslam::bow
