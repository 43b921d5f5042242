// Edge cases of the extractor: tiny, empty and colour images, zero budget, reuse across frame sizes.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <string>
#include <thread>
#include <vector>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/feature/orb_descriptor.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/util/error.h"
#include "feature_test_data.h"

namespace crowdslam::feature {
namespace {

cv::Mat checkerboard(cv::Size size, int square) {
  cv::Mat image(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      image.at<std::uint8_t>(y, x) = ((x / square + y / square) % 2) ? 220 : 30;
    }
  }
  return image;
}

TEST(ORBExtractorEdge, ImagesSmallerThanThePatchGiveNoKeypoints) {
  ORBExtractor extractor;
  for (const int side : {1, 5, 20, 38}) {
    std::vector<cv::KeyPoint> keypoints(3);
    cv::Mat descriptors(7, 32, CV_8UC1);
    extractor.extract(checkerboard(cv::Size(side, side), 4), 1000, keypoints, descriptors);
    EXPECT_TRUE(keypoints.empty()) << side;
    EXPECT_EQ(descriptors.rows, 0) << side;
  }
}

TEST(ORBExtractorEdge, SmallImagesKeepKeypointsInsideTheDescriptorBorder) {
  ORBExtractor extractor;
  for (const cv::Size size : {cv::Size(39, 39), cv::Size(45, 60), cv::Size(80, 41), cv::Size(120, 90)}) {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    const cv::Mat image = checkerboard(size, 5);
    extractor.extract(image, 1000, keypoints, descriptors);
    EXPECT_EQ(descriptors.rows, static_cast<int>(keypoints.size()));
    for (const cv::KeyPoint& k : keypoints) {
      const cv::Mat& level = extractor.pyramid()[k.octave];
      const cv::Point2f p = k.pt * extractor.inv_scale_factors()[k.octave];
      EXPECT_GE(p.x, kOrbEdgeThreshold);
      EXPECT_GE(p.y, kOrbEdgeThreshold);
      EXPECT_LT(p.x, level.cols - kOrbEdgeThreshold);
      EXPECT_LT(p.y, level.rows - kOrbEdgeThreshold);
    }
  }
}

TEST(ORBExtractorEdge, ZeroBudgetGivesNothing) {
  ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints(3);
  cv::Mat descriptors;
  extractor.extract(checkerboard(cv::Size(640, 480), 8), 0, keypoints, descriptors);
  EXPECT_TRUE(keypoints.empty());
  EXPECT_EQ(descriptors.rows, 0);
}

TEST(ORBExtractorEdge, EmptyOrColourImagesAreInputErrors) {
  ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  try {
    extractor.extract(cv::Mat(), 100, keypoints, descriptors);
    ADD_FAILURE() << "no error for an empty image";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("empty image"), std::string::npos) << error.what();
  }
  try {
    extractor.extract(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(9)), 100, keypoints, descriptors);
    ADD_FAILURE() << "no error for a colour image";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("CV_8UC1"), std::string::npos) << error.what();
  }
}

// The extractor keeps buffers between calls; that must not leak state from one frame into the next.
TEST(ORBExtractorEdge, ReuseAcrossFrameSizesMatchesAFreshExtractor) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  cv::Mat half;
  cv::resize(gray, half, cv::Size(320, 240));
  const cv::Mat view = gray(cv::Rect(40, 30, 500, 400));  // not continuous in memory
  ORBExtractor reused;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (const cv::Mat* image : std::vector<const cv::Mat*>{&gray, &half, &view, &gray}) {
    reused.extract(*image, 800, keypoints, descriptors);
    ORBExtractor fresh;
    std::vector<cv::KeyPoint> fresh_keypoints;
    cv::Mat fresh_descriptors;
    fresh.extract(image->clone(), 800, fresh_keypoints, fresh_descriptors);
    ASSERT_EQ(keypoints.size(), fresh_keypoints.size()) << image->size();
    for (std::size_t i = 0; i < keypoints.size(); ++i) {
      ASSERT_EQ(keypoints[i].pt, fresh_keypoints[i].pt);
      ASSERT_EQ(keypoints[i].angle, fresh_keypoints[i].angle);
    }
    EXPECT_EQ(cv::norm(descriptors, fresh_descriptors, cv::NORM_HAMMING), 0) << image->size();
  }
}

// One extractor per thread: extractors share no state, so concurrent runs give the sequential result.
TEST(ORBExtractorEdge, SeparateExtractorsRunConcurrently) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ORBExtractor reference_extractor;
  std::vector<cv::KeyPoint> reference;
  cv::Mat reference_descriptors;
  reference_extractor.extract(gray, 1000, reference, reference_descriptors);

  std::vector<cv::Mat> descriptors(2);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < descriptors.size(); ++t) {
    threads.emplace_back([&gray, &descriptors, t] {
      ORBExtractor extractor;
      std::vector<cv::KeyPoint> keypoints;
      for (int repeat = 0; repeat < 5; ++repeat) extractor.extract(gray, 1000, keypoints, descriptors[t]);
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (const cv::Mat& result : descriptors) {
    ASSERT_EQ(result.rows, reference_descriptors.rows);
    EXPECT_EQ(cv::norm(result, reference_descriptors, cv::NORM_HAMMING), 0);
  }
}

TEST(ToGray, ConvertsColourInTheGivenChannelOrder) {
  const cv::Mat blue_first(4, 4, CV_8UC3, cv::Scalar(255, 0, 0));
  // BGR: pure blue -> 0.114 * 255; read as RGB it is pure red -> 0.299 * 255.
  EXPECT_NEAR(to_gray(blue_first, ColorOrder::kBgr).at<std::uint8_t>(0, 0), 29, 1);
  EXPECT_NEAR(to_gray(blue_first, ColorOrder::kRgb).at<std::uint8_t>(0, 0), 76, 1);
  const cv::Mat with_alpha(4, 4, CV_8UC4, cv::Scalar(255, 0, 0, 255));
  EXPECT_NEAR(to_gray(with_alpha, ColorOrder::kBgr).at<std::uint8_t>(0, 0), 29, 1);
  const cv::Mat gray(4, 4, CV_8UC1, cv::Scalar(77));
  EXPECT_EQ(to_gray(gray).data, gray.data);
  EXPECT_THROW(to_gray(cv::Mat()), InputError);
  EXPECT_THROW(to_gray(cv::Mat(4, 4, CV_16UC1)), InputError);
}

}  // namespace
}  // namespace crowdslam::feature
