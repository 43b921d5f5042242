// Place recognition with real images: a small vocabulary trained on OpenCV's sample images (from the
// opencv-doc package) tells two Bonn frames of the same view apart from a frame far away in the sequence.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/bow/vocabulary.h"
#include "test_support.h"

namespace crowdslam::bow {
namespace {

const std::filesystem::path kOpencvData = "/usr/share/doc/opencv-doc/examples/data";

cv::Mat orb_descriptors(const std::filesystem::path& path, int num_features) {
  const cv::Mat gray = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  if (gray.empty()) return {};
  feature::ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  extractor.extract(gray, num_features, keypoints, descriptors);
  return descriptors;
}

TEST(VocabularyImages, FrameScoresHigherAgainstItsOwnViewThanAgainstAFarFrame) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const std::vector<std::string> training = {"building.jpg", "home.jpg",  "fruits.jpg", "baboon.jpg",
                                             "aero1.jpg",    "board.jpg", "left01.jpg", "leuvenA.jpg"};
  std::vector<cv::Mat> train_descriptors;
  for (const auto& name : training) {
    cv::Mat d = orb_descriptors(kOpencvData / name, 500);
    if (!d.empty()) train_descriptors.push_back(d);
  }
  if (train_descriptors.size() < 4) GTEST_SKIP() << "opencv-doc sample images missing in " << kOpencvData;
  VocabularyTrainOptions options;
  options.k = 5;
  options.levels = 3;
  const Vocabulary voc = Vocabulary::train(train_descriptors, options);
  EXPECT_GT(voc.num_words(), 60u);

  const auto rgb = crowdslam::test::shared_data("bonn_crowd") / "rgb";
  // Frames 0 and 2 (66 ms apart) see the same view; frame 599 (20 s later) is turned by about 35 degrees.
  BowVector first;
  BowVector near;
  BowVector far;
  voc.transform(orb_descriptors(rgb / "1548339819.87426.jpg", 1000), first);
  voc.transform(orb_descriptors(rgb / "1548339819.94105.jpg", 1000), near);
  voc.transform(orb_descriptors(rgb / "1548339839.95090.jpg", 1000), far);
  ASSERT_FALSE(first.empty());
  const double self = l1_score(first, first);
  const double same_view = l1_score(first, near);
  const double other_view = l1_score(first, far);
  RecordProperty("same_view", std::to_string(same_view));
  RecordProperty("other_view", std::to_string(other_view));
  EXPECT_DOUBLE_EQ(self, 1.0);
  EXPECT_GT(self, other_view);
  EXPECT_GT(same_view, other_view);
  EXPECT_DOUBLE_EQ(same_view, l1_score(near, first));
  std::printf("same view %.3f, other view %.3f\n", same_view, other_view);
}

}  // namespace
}  // namespace crowdslam::bow
