// Bags of words computed on demand: the frame gets a copy of its features with the bag of words of its
// descriptors; the original (shared with others) is left as it was.
#include <gtest/gtest.h>

#include <random>

#include "crowdslam/tracking/frame_bow.h"

using namespace crowdslam;

TEST(FrameBow, EnsureBowAddsTheVocabularysBagOfWordsToACopy) {
  std::mt19937 rng(7);
  auto random_descriptors = [&](int rows) {
    cv::Mat d(rows, 32, CV_8UC1);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < 32; ++c) d.at<uint8_t>(r, c) = static_cast<uint8_t>(rng() & 0xFF);
    }
    return d;
  };
  bow::VocabularyTrainOptions options;
  options.k = 4;
  options.levels = 3;
  const auto vocabulary = bow::Vocabulary::train({random_descriptors(300), random_descriptors(300)}, options);

  auto original = std::make_shared<map::FrameFeatures>();
  original->descriptors = random_descriptors(120);
  original->keys.resize(120);
  original->keys_un.resize(120);
  map::Frame frame(3, 0.0, std::make_shared<geometry::PinholeCamera>(), std::make_shared<map::ScaleLevels>(1.2f, 8),
                   original);
  ASSERT_FALSE(frame.features->has_bow());
  tracking::ensure_bow(frame, vocabulary);

  bow::BowVector expected;
  bow::FeatureVector expected_index;
  vocabulary.transform(original->descriptors, expected, expected_index);
  ASSERT_TRUE(frame.features->has_bow());
  EXPECT_EQ(frame.features->bow, expected);
  EXPECT_EQ(frame.features->bow_features, expected_index);
  EXPECT_NE(frame.features.get(), original.get());
  EXPECT_FALSE(original->has_bow());                                   // the shared original is untouched
  EXPECT_EQ(frame.features->descriptors.data, original->descriptors.data);  // descriptors shared, not copied
  EXPECT_EQ(frame.features->size(), 120u);

  // A second call keeps what is there.
  const auto* with_bow = frame.features.get();
  tracking::ensure_bow(frame, vocabulary);
  EXPECT_EQ(frame.features.get(), with_bow);
}
