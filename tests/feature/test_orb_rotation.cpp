// Rotation invariance of the extractor on a real frame: keypoints found again after rotating the image
// about its centre carry the rotated orientation and nearly the same steered descriptor, while plain
// (unsteered) BRIEF at the same keypoints does not survive the rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/feature/orb_descriptor.h"
#include "crowdslam/feature/orb_extractor.h"
#include "feature_test_data.h"

namespace crowdslam::feature {
namespace {

constexpr int kGoodMatchBits = 50;

struct View {
  ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<cv::Mat> blurred;  // per level, for the unsteered descriptors

  explicit View(const cv::Mat& gray) {
    extractor.extract(gray, 1500, keypoints, descriptors);
    for (const cv::Mat& level : extractor.pyramid()) {
      cv::Mat b;
      cv::GaussianBlur(level, b, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
      blurred.push_back(b);
    }
  }
  std::vector<std::uint8_t> unsteered(int index) const {
    const cv::KeyPoint& k = keypoints[index];
    std::vector<std::uint8_t> descriptor(kDescriptorBytes);
    steered_brief(blurred[k.octave], k.pt * extractor.inv_scale_factors()[k.octave], 0.f, descriptor.data());
    return descriptor;
  }
};

struct RotationScore {
  int matches = 0;
  double steered_good = 0;      // fraction of matches with a steered distance below kGoodMatchBits
  double unsteered_good = 0;    // same for BRIEF without steering
  double angle_consistent = 0;  // fraction whose orientation turned by the rotation (within 10 degrees)
};

double angle_difference_deg(double a, double b) {
  const double d = std::fmod(std::fabs(a - b), 360.0);
  return d > 180.0 ? 360.0 - d : d;
}

RotationScore score_rotation(const cv::Mat& gray, double rotation_deg) {
  const cv::Point2f center((gray.cols - 1) / 2.f, (gray.rows - 1) / 2.f);
  const cv::Mat rotation = cv::getRotationMatrix2D(center, rotation_deg, 1.0);
  cv::Mat rotated;
  cv::warpAffine(gray, rotated, rotation, gray.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  const View original(gray);
  const View turned(rotated);

  RotationScore score;
  int steered_good = 0;
  int unsteered_good = 0;
  int angle_consistent = 0;
  for (int i = 0; i < static_cast<int>(original.keypoints.size()); ++i) {
    const cv::KeyPoint& k = original.keypoints[i];
    const cv::Point2f expected(
        static_cast<float>(rotation.at<double>(0, 0) * k.pt.x + rotation.at<double>(0, 1) * k.pt.y +
                           rotation.at<double>(0, 2)),
        static_cast<float>(rotation.at<double>(1, 0) * k.pt.x + rotation.at<double>(1, 1) * k.pt.y +
                           rotation.at<double>(1, 2)));
    const float tolerance = 1.5f * original.extractor.scale_factors()[k.octave];
    int best = -1;
    float best_distance = tolerance;
    for (int j = 0; j < static_cast<int>(turned.keypoints.size()); ++j) {
      const cv::KeyPoint& candidate = turned.keypoints[j];
      if (candidate.octave != k.octave) continue;
      const float distance = static_cast<float>(cv::norm(candidate.pt - expected));
      if (distance <= best_distance) {
        best_distance = distance;
        best = j;
      }
    }
    if (best < 0) continue;
    ++score.matches;
    steered_good += hamming_distance(original.descriptors.ptr<std::uint8_t>(i),
                                     turned.descriptors.ptr<std::uint8_t>(best)) < kGoodMatchBits;
    unsteered_good +=
        hamming_distance(original.unsteered(i).data(), turned.unsteered(best).data()) < kGoodMatchBits;
    // getRotationMatrix2D turns the picture counter-clockwise: image-axis angles (y down) decrease.
    angle_consistent += angle_difference_deg(turned.keypoints[best].angle, k.angle - rotation_deg) < 10.0;
  }
  if (score.matches > 0) {
    score.steered_good = double(steered_good) / score.matches;
    score.unsteered_good = double(unsteered_good) / score.matches;
    score.angle_consistent = double(angle_consistent) / score.matches;
  }
  return score;
}

class ORBRotation : public ::testing::TestWithParam<double> {};

TEST_P(ORBRotation, SteeredDescriptorsSurviveRotationUnsteeredDoNot) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  const cv::Mat gray = testing::bonn_gray();
  ASSERT_FALSE(gray.empty());
  const RotationScore score = score_rotation(gray, GetParam());
  RecordProperty("matches", score.matches);
  RecordProperty("steered_good_percent", static_cast<int>(100 * score.steered_good));
  RecordProperty("unsteered_good_percent", static_cast<int>(100 * score.unsteered_good));
  ASSERT_GE(score.matches, 150);
  EXPECT_GT(score.steered_good, 0.8);
  EXPECT_GT(score.angle_consistent, 0.8);
  EXPECT_LT(score.unsteered_good, 0.3);
}

INSTANTIATE_TEST_SUITE_P(Angles, ORBRotation, ::testing::Values(30.0, 90.0));

}  // namespace
}  // namespace crowdslam::feature
