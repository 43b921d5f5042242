#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/feature/orb_descriptor.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/util/error.h"
#include "feature_test_data.h"

namespace crowdslam::feature {
namespace {

struct Extraction {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

Extraction extract(ORBExtractor& extractor, const cv::Mat& gray, int num_features) {
  Extraction result;
  extractor.extract(gray, num_features, result.keypoints, result.descriptors);
  return result;
}

void expect_option_error(ORBExtractor::Options options, const std::string& name) {
  try {
    options.check();
    ADD_FAILURE() << "no error for bad " << name;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(name), std::string::npos) << error.what();
  }
  EXPECT_THROW(ORBExtractor{options}, InputError);
}

TEST(ORBExtractorOptions, RejectBadValuesNamingTheOption) {
  ORBExtractor::Options options;
  EXPECT_NO_THROW(options.check());
  options.num_features = -1;
  expect_option_error(options, "num_features");
  options = {};
  options.scale_factor = 1.f;
  expect_option_error(options, "scale_factor");
  options.scale_factor = std::nanf("");
  expect_option_error(options, "scale_factor");
  options = {};
  options.num_levels = 0;
  expect_option_error(options, "num_levels");
  options = {};
  options.ini_th_fast = 0;
  expect_option_error(options, "ini_th_fast");
  options = {};
  options.min_th_fast = 21;
  expect_option_error(options, "min_th_fast");
}

TEST(ORBExtractor, ExposesScaleAndSigmaPerLevel) {
  ORBExtractor extractor;
  ASSERT_EQ(extractor.num_levels(), 8);
  ASSERT_EQ(extractor.scale_factors().size(), 8u);
  for (int level = 0; level < 8; ++level) {
    const double scale = std::pow(1.2, level);
    EXPECT_NEAR(extractor.scale_factors()[level], scale, 1e-5 * scale);
    EXPECT_NEAR(extractor.inv_scale_factors()[level], 1.0 / scale, 1e-6);
    EXPECT_NEAR(extractor.level_sigma2()[level], scale * scale, 1e-5 * scale * scale);
    EXPECT_NEAR(extractor.inv_level_sigma2()[level], 1.0 / (scale * scale), 1e-6);
  }
}

TEST(ORBExtractor, SharesTheBudgetAmongLevelsByArea) {
  ORBExtractor extractor;
  for (const int budget : {1000, 137, 2000}) {
    const std::vector<int> counts = extractor.features_per_level(budget);
    ASSERT_EQ(counts.size(), 8u);
    int sum = 0;
    for (const int count : counts) sum += count;
    EXPECT_EQ(sum, budget);
    // Geometric series with ratio 1/1.44: n0 = N (1 - r) / (1 - r^8).
    const double r = 1.0 / 1.44;
    const double n0 = budget * (1 - r) / (1 - std::pow(r, 8));
    for (int level = 0; level < 7; ++level) EXPECT_NEAR(counts[level], n0 * std::pow(r, level), 0.51);
  }
  EXPECT_EQ(extractor.features_per_level(0), std::vector<int>(8, 0));
  ORBExtractor::Options one_level;
  one_level.num_levels = 1;
  EXPECT_EQ(ORBExtractor(one_level).features_per_level(500), std::vector<int>{500});
}

TEST(ORBExtractor, MeetsTheBudgetOnARealFrameAndFollowsItsChanges) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ASSERT_FALSE(gray.empty());
  ORBExtractor extractor;
  for (const int budget : {1000, 500, 1500, 1000}) {
    const Extraction result = extract(extractor, gray, budget);
    EXPECT_GE(static_cast<int>(result.keypoints.size()), budget * 97 / 100) << "budget " << budget;
    EXPECT_LE(static_cast<int>(result.keypoints.size()), budget) << "budget " << budget;
    EXPECT_EQ(result.descriptors.rows, static_cast<int>(result.keypoints.size()));
    EXPECT_EQ(result.descriptors.cols, kDescriptorBytes);
    EXPECT_EQ(result.descriptors.type(), CV_8UC1);
  }
}

TEST(ORBExtractor, PerLevelCountsFollowLevelArea) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ORBExtractor extractor;
  const Extraction result = extract(extractor, gray, 1000);
  std::vector<int> per_level(8, 0);
  for (const cv::KeyPoint& k : result.keypoints) ++per_level[k.octave];
  const std::vector<int> wanted = extractor.features_per_level(1000);
  for (int level = 0; level < 8; ++level) {
    EXPECT_LE(per_level[level], wanted[level]) << "level " << level;
    EXPECT_GE(per_level[level], wanted[level] * 9 / 10) << "level " << level;
  }
  // Level 0 holds about 1 - 1/1.2^2 of all features.
  EXPECT_NEAR(per_level[0] / 1000.0, (1 - 1 / 1.44) / (1 - std::pow(1 / 1.44, 8)), 0.02);
}

// Keypoints are in original-image pixels; dividing by the level scale must land on the level image,
// inside the descriptor border, and recomputing the descriptor there reproduces the extractor's row.
TEST(ORBExtractor, OctaveScaleAndPositionAreConsistent) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ORBExtractor extractor;
  const Extraction result = extract(extractor, gray, 1000);
  ASSERT_FALSE(result.keypoints.empty());
  std::vector<cv::Mat> blurred(8);
  int previous_octave = 0;
  for (std::size_t i = 0; i < result.keypoints.size(); ++i) {
    const cv::KeyPoint& k = result.keypoints[i];
    ASSERT_GE(k.octave, previous_octave) << "keypoints are ordered by level";
    previous_octave = k.octave;
    ASSERT_LT(k.octave, 8);
    const float scale = extractor.scale_factors()[k.octave];
    EXPECT_FLOAT_EQ(k.size, 31.f * scale);
    EXPECT_GE(k.angle, 0.f);
    EXPECT_LT(k.angle, 360.f);
    EXPECT_GT(k.response, 0.f);
    const cv::Mat& level_image = extractor.pyramid()[k.octave];
    // Level-0 coordinates map back with the pixel-centre convention: x = (x0 + 0.5) * w / w0 - 0.5.
    const cv::Point2f level_pt((k.pt.x + 0.5f) * level_image.cols / gray.cols - 0.5f,
                               (k.pt.y + 0.5f) * level_image.rows / gray.rows - 0.5f);
    EXPECT_NEAR(level_pt.x, std::round(level_pt.x), 1e-3) << "FAST positions are whole level pixels";
    EXPECT_GE(level_pt.x, kOrbEdgeThreshold - 1e-3);
    EXPECT_GE(level_pt.y, kOrbEdgeThreshold - 1e-3);
    EXPECT_LT(level_pt.x, level_image.cols - kOrbEdgeThreshold);
    EXPECT_LT(level_pt.y, level_image.rows - kOrbEdgeThreshold);
    EXPECT_NEAR(k.angle, intensity_centroid_angle(level_image, level_pt), 1e-3);
    if (blurred[k.octave].empty()) {
      cv::GaussianBlur(level_image, blurred[k.octave], cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
    }
    std::uint8_t descriptor[kDescriptorBytes];
    steered_brief(blurred[k.octave], level_pt, k.angle, descriptor);
    EXPECT_EQ(hamming_distance(descriptor, result.descriptors.ptr<std::uint8_t>(static_cast<int>(i))), 0)
        << "keypoint " << i << " octave " << k.octave;
  }
  EXPECT_GT(previous_octave, 5) << "coarse levels contribute";
  // The pyramid follows the scale factors.
  for (int level = 1; level < 8; ++level) {
    EXPECT_EQ(extractor.pyramid()[level].cols, cvRound(640 * extractor.inv_scale_factors()[level]));
    EXPECT_EQ(extractor.pyramid()[level].rows, cvRound(480 * extractor.inv_scale_factors()[level]));
  }
}

int occupied_cells(const std::vector<cv::KeyPoint>& keypoints, cv::Size size, int grid) {
  std::vector<int> counts(grid * grid, 0);
  for (const cv::KeyPoint& k : keypoints) {
    const int col = std::min(grid - 1, static_cast<int>(k.pt.x * grid / size.width));
    const int row = std::min(grid - 1, static_cast<int>(k.pt.y * grid / size.height));
    ++counts[row * grid + col];
  }
  return static_cast<int>(std::count_if(counts.begin(), counts.end(), [](int c) { return c > 0; }));
}

std::vector<cv::KeyPoint> fast_top_n(const cv::Mat& gray, int threshold, int n) {
  std::vector<cv::KeyPoint> keypoints;
  cv::FAST(gray, keypoints, threshold, true);
  cv::KeyPointsFilter::runByImageBorder(keypoints, gray.size(), kOrbEdgeThreshold);
  cv::KeyPointsFilter::retainBest(keypoints, n);
  return keypoints;
}

// Faint texture everywhere, strong texture in the left quarter: the strongest FAST corners all sit on the
// left, while the grid (with its low threshold) and the quadtree reach every cell.
TEST(ORBExtractor, SpreadsKeypointsOverTheImageUnlikeFastTopN) {
  cv::Mat noise(480, 640, CV_32FC1);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
  cv::Mat amplitude(480, 640, CV_32FC1, cv::Scalar(60.f));
  amplitude(cv::Rect(0, 0, 160, 480)).setTo(600.f);
  cv::Mat textured;
  cv::Mat(noise.mul(amplitude) + 128.f).convertTo(textured, CV_8UC1);

  ORBExtractor extractor;
  const Extraction result = extract(extractor, textured, 1000);
  EXPECT_GE(result.keypoints.size(), 970u);
  EXPECT_EQ(occupied_cells(result.keypoints, textured.size(), 4), 16);
  const auto fast = fast_top_n(textured, 20, 1000);
  EXPECT_LE(occupied_cells(fast, textured.size(), 4), 8) << "the test image does not separate the methods";
}

TEST(ORBExtractor, CoversEveryCellWithCornersOnARealFrame) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ORBExtractor extractor;
  const Extraction result = extract(extractor, gray, 1000);
  // Cells of a 4 x 4 grid that have any FAST corner at the low threshold get keypoints.
  const auto all_corners = fast_top_n(gray, 7, 1 << 30);
  EXPECT_EQ(occupied_cells(result.keypoints, gray.size(), 4), occupied_cells(all_corners, gray.size(), 4));
  // On a finer grid the quadtree covers clearly more cells than the 1000 strongest FAST corners.
  const auto fast = fast_top_n(gray, 20, 1000);
  EXPECT_GE(occupied_cells(result.keypoints, gray.size(), 8), occupied_cells(fast, gray.size(), 8) + 5);
}

}  // namespace
}  // namespace crowdslam::feature
