// Extraction in two steps (ORBExtractor::prepare, then extract from the PreparedImage): prepared on
// another thread and finished with any budget, it gives what extract(gray, ...) gives.
#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/util/error.h"
#include "feature_test_data.h"

namespace crowdslam::feature {
namespace {

void expect_same(const std::vector<cv::KeyPoint>& a, const cv::Mat& da, const std::vector<cv::KeyPoint>& b,
                 const cv::Mat& db, int budget) {
  ASSERT_EQ(a.size(), b.size()) << budget;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].pt, b[i].pt) << budget << " keypoint " << i;
    ASSERT_EQ(a[i].angle, b[i].angle) << budget << " keypoint " << i;
    ASSERT_EQ(a[i].octave, b[i].octave) << budget << " keypoint " << i;
    ASSERT_EQ(a[i].response, b[i].response) << budget << " keypoint " << i;
  }
  ASSERT_EQ(da.rows, db.rows);
  EXPECT_EQ(cv::norm(da, db, cv::NORM_HAMMING), 0) << budget;
}

TEST(ORBPrepare, PreparedOnAnotherThreadGivesTheDirectResultForEveryBudget) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  PreparedImage prepared;
  std::thread reader([&] {
    ORBExtractor preparer;
    preparer.prepare(gray, prepared);
  });
  reader.join();
  ORBExtractor finisher;
  ORBExtractor direct;
  // One preparation serves several budgets (it is not changed by extract), the largest FNU's 2.2x.
  for (const int budget : {2200, 300, 1000}) {
    std::vector<cv::KeyPoint> keypoints;
    std::vector<cv::KeyPoint> direct_keypoints;
    cv::Mat descriptors;
    cv::Mat direct_descriptors;
    finisher.extract(prepared, budget, keypoints, descriptors);
    direct.extract(gray, budget, direct_keypoints, direct_descriptors);
    EXPECT_GT(keypoints.size(), static_cast<std::size_t>(budget) * 9 / 10);
    expect_same(keypoints, descriptors, direct_keypoints, direct_descriptors, budget);
    // The stereo matcher reads the pyramid of the last extraction: the prepared levels themselves.
    ASSERT_EQ(finisher.pyramid().size(), prepared.pyramid.size());
    for (std::size_t level = 0; level < prepared.pyramid.size(); ++level) {
      EXPECT_EQ(finisher.pyramid()[level].data, prepared.pyramid[level].data) << level;
    }
  }
  EXPECT_EQ(prepared.gray.data, gray.data);  // level 0 is the caller's image, not a copy
}

TEST(ORBPrepare, APreparationFromOtherOptionsOrABadImageIsAnInputError) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  ORBExtractor::Options four_levels;
  four_levels.num_levels = 4;
  ORBExtractor other(four_levels);
  PreparedImage prepared;
  other.prepare(testing::bonn_gray(), prepared);
  ORBExtractor extractor;  // 8 levels
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  try {
    extractor.extract(prepared, 1000, keypoints, descriptors);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("4 levels"), std::string::npos) << e.what();
  }
  EXPECT_THROW(extractor.prepare(cv::Mat(), prepared), InputError);
  EXPECT_THROW(extractor.prepare(cv::Mat(40, 40, CV_8UC3, cv::Scalar::all(0)), prepared), InputError);
  EXPECT_THROW(extractor.extract(PreparedImage{}, 1000, keypoints, descriptors), InputError);
}

}  // namespace
}  // namespace crowdslam::feature
