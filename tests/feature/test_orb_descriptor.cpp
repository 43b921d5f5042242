#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "crowdslam/feature/orb_descriptor.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/feature/orb_pattern.h"
#include "feature_test_data.h"

namespace crowdslam::feature {
namespace {

double angle_difference_deg(double a, double b) {
  const double d = std::fmod(std::fabs(a - b), 360.0);
  return d > 180.0 ? 360.0 - d : d;
}

TEST(OrbPattern, HasTwoHundredFiftySixPairsInsideThePatch) {
  ASSERT_EQ(orb_pattern().size(), 256u * 4u);
  int distinct_pairs = 0;
  for (int i = 0; i < kOrbPatternSize; ++i) {
    const std::int8_t* t = &orb_pattern()[4 * i];
    for (int k = 0; k < 4; ++k) {
      EXPECT_GE(t[k], -13);
      EXPECT_LE(t[k], 12);
    }
    distinct_pairs += (t[0] != t[2] || t[1] != t[3]) ? 1 : 0;
  }
  EXPECT_EQ(distinct_pairs, kOrbPatternSize);
  // First and last tests of Rublee et al.'s learned pattern (as in OpenCV's bit_pattern_31_).
  EXPECT_EQ((std::vector<int>(orb_pattern().begin(), orb_pattern().begin() + 4)),
            (std::vector<int>{8, -3, 9, 5}));
  EXPECT_EQ((std::vector<int>(orb_pattern().end() - 4, orb_pattern().end())),
            (std::vector<int>{-1, -6, 0, -11}));
}

TEST(CircleHalfWidths, DescribeASymmetricDiscOfRadiusFifteen) {
  const auto& widths = circle_half_widths();
  EXPECT_EQ(widths[0], 15);
  EXPECT_EQ(widths[15], 3);
  for (int v = 0; v <= 15; ++v) {
    // Rows of a disc of radius 15 (rounded): never wider than the circle allows by more than rounding.
    EXPECT_LE(widths[v] * widths[v] + v * v, 15 * 15 + 15) << "row " << v;
    if (v > 0) {
      EXPECT_LE(widths[v], widths[v - 1]);
    }
  }
  for (int u = -15; u <= 15; ++u) {
    for (int v = -15; v <= 15; ++v) {
      const bool inside = std::abs(u) <= widths[std::abs(v)];
      const bool transposed_inside = std::abs(v) <= widths[std::abs(u)];
      EXPECT_EQ(inside, transposed_inside) << u << "," << v;
    }
  }
}

// A linear ramp rising along direction theta has its intensity centroid in that direction.
TEST(IntensityCentroidAngle, FollowsTheGradientDirectionOfARamp) {
  for (const double theta_deg : {0.0, 30.0, 90.0, 135.0, 200.0, 315.0}) {
    const double theta = theta_deg * CV_PI / 180.0;
    cv::Mat image(41, 41, CV_8UC1);
    for (int y = 0; y < image.rows; ++y) {
      for (int x = 0; x < image.cols; ++x) {
        const double along = std::cos(theta) * (x - 20) + std::sin(theta) * (y - 20);
        image.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(128.0 + 4.0 * along);
      }
    }
    const float angle = intensity_centroid_angle(image, cv::Point2f(20.f, 20.f));
    EXPECT_LT(angle_difference_deg(angle, theta_deg), 1.0) << "theta " << theta_deg << " got " << angle;
    EXPECT_GE(angle, 0.f);
    EXPECT_LT(angle, 360.f);
  }
}

TEST(IntensityCentroidAngle, EqualsOpenCvOrbOrientationOnARealFrame) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ASSERT_FALSE(gray.empty());
  const auto orb = cv::ORB::create(500, 1.2f, 1, 31, 0, 2, cv::ORB::FAST_SCORE);
  std::vector<cv::KeyPoint> keypoints;
  orb->detect(gray, keypoints);
  ASSERT_GT(keypoints.size(), 100u);
  int compared = 0;
  for (const cv::KeyPoint& keypoint : keypoints) {
    EXPECT_NEAR(intensity_centroid_angle(gray, keypoint.pt), keypoint.angle, 1e-3) << "at " << keypoint.pt;
    ++compared;
  }
  EXPECT_EQ(compared, static_cast<int>(keypoints.size()));
}

struct LevelZero {
  std::vector<cv::KeyPoint> keypoints;
  std::vector<int> rows;  // row of each keypoint in the extractor's descriptors
  cv::Mat descriptors;
};

LevelZero extract_level_zero(const cv::Mat& gray) {
  ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  LevelZero result;
  extractor.extract(gray, 2000, keypoints, result.descriptors);
  for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
    if (keypoints[i].octave != 0) continue;
    result.keypoints.push_back(keypoints[i]);
    result.rows.push_back(i);
  }
  return result;
}

cv::Mat opencv_orb_descriptors(const cv::Mat& gray, const std::vector<cv::KeyPoint>& keypoints) {
  const auto orb = cv::ORB::create(2000, 1.2f, 1, kOrbEdgeThreshold, 0, 2, cv::ORB::FAST_SCORE);
  std::vector<cv::KeyPoint> kept = keypoints;
  cv::Mat descriptors;
  orb->compute(gray, kept, descriptors);
  EXPECT_EQ(kept.size(), keypoints.size()) << "cv::ORB dropped keypoints";
  for (std::size_t i = 0; i < std::min(kept.size(), keypoints.size()); ++i) {
    EXPECT_EQ(kept[i].pt, keypoints[i].pt);
    EXPECT_EQ(kept[i].angle, keypoints[i].angle);
  }
  return descriptors;
}

// The pattern, rotation and rounding are cv::ORB's: on the image cv::ORB samples (it blurs the level as
// a view into a reflect-padded buffer), steered_brief gives the very same bits for the same keypoints.
TEST(SteeredBrief, BitIdenticalToOpenCvOrbOnTheSameBlurredImage) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ASSERT_FALSE(gray.empty());
  const LevelZero level0 = extract_level_zero(gray);
  ASSERT_GT(level0.keypoints.size(), 300u);
  const cv::Mat expected = opencv_orb_descriptors(gray, level0.keypoints);
  ASSERT_EQ(expected.rows, static_cast<int>(level0.keypoints.size()));

  cv::Mat padded;
  cv::copyMakeBorder(gray, padded, 20, 20, 20, 20, cv::BORDER_REFLECT_101);
  cv::Mat blurred = padded(cv::Rect(20, 20, gray.cols, gray.rows));
  cv::GaussianBlur(blurred, blurred, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);

  int identical = 0;
  std::uint8_t descriptor[32];
  for (std::size_t i = 0; i < level0.keypoints.size(); ++i) {
    steered_brief(blurred, level0.keypoints[i].pt, level0.keypoints[i].angle, descriptor);
    identical += cv::norm(cv::Mat(1, 32, CV_8UC1, descriptor), expected.row(static_cast<int>(i)),
                          cv::NORM_HAMMING) == 0;
  }
  EXPECT_EQ(identical, static_cast<int>(level0.keypoints.size()));
}

// The extractor blurs with OpenCV's bit-exact fixed-point Gaussian (as ORB-SLAM2 does on OpenCV 4), which
// rounds a few pixels differently from the path cv::ORB takes: descriptors differ by at most a few bits.
TEST(SteeredBrief, ExtractorDescriptorsAgreeWithOpenCvOrbUpToBlurRounding) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ASSERT_FALSE(gray.empty());
  const LevelZero level0 = extract_level_zero(gray);
  const cv::Mat expected = opencv_orb_descriptors(gray, level0.keypoints);
  ASSERT_EQ(expected.rows, static_cast<int>(level0.keypoints.size()));
  int identical = 0;
  int within_four_bits = 0;
  double worst = 0;
  for (std::size_t i = 0; i < level0.keypoints.size(); ++i) {
    const double distance =
        cv::norm(level0.descriptors.row(level0.rows[i]), expected.row(static_cast<int>(i)), cv::NORM_HAMMING);
    identical += distance == 0;
    within_four_bits += distance <= 4;
    worst = std::max(worst, distance);
  }
  const double count = static_cast<double>(level0.keypoints.size());
  EXPECT_GT(identical, 0.6 * count);
  EXPECT_GT(within_four_bits, 0.97 * count);
  EXPECT_LE(worst, 20) << "far beyond a rounding difference";
  RecordProperty("identical_percent", static_cast<int>(100 * identical / count));
  RecordProperty("worst_bits", static_cast<int>(worst));
}

}  // namespace
}  // namespace crowdslam::feature
