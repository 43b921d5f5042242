// Bag-of-words guided matching on a real image and a copy warped by a known homography (rotation, scale,
// shift): the matches must agree with the homography. The vocabulary is trained in the test on other
// sample images of the opencv-doc package.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/match/bow_search.h"

using namespace crowdslam;

namespace {

const std::filesystem::path kOpencvData = "/usr/share/doc/opencv-doc/examples/data";

cv::Mat gray(const std::string& name) { return cv::imread((kOpencvData / name).string(), cv::IMREAD_GRAYSCALE); }

struct BowSearchTest : ::testing::Test {
  bow::Vocabulary vocabulary;
  std::shared_ptr<geometry::PinholeCamera> camera = std::make_shared<geometry::PinholeCamera>();
  std::shared_ptr<map::ScaleLevels> levels = std::make_shared<map::ScaleLevels>(1.2f, 8);
  map::Map map;
  cv::Mat image;
  cv::Mat warped;
  cv::Matx33d homography;  // warped pixel = H * image pixel

  void SetUp() override {
    image = gray("graf1.png");
    if (image.empty()) GTEST_SKIP() << "opencv-doc sample images missing in " << kOpencvData;
    std::vector<cv::Mat> training;
    for (const char* name : {"building.jpg", "home.jpg", "fruits.jpg", "aero1.jpg", "board.jpg", "left01.jpg",
                             "leuvenA.jpg", "box_in_scene.png"}) {
      const cv::Mat g = gray(name);
      if (g.empty()) continue;
      std::vector<cv::KeyPoint> keys;
      cv::Mat descriptors;
      feature::ORBExtractor().extract(g, 500, keys, descriptors);
      training.push_back(descriptors);
    }
    ASSERT_GE(training.size(), 6u);
    bow::VocabularyTrainOptions options;
    options.k = 10;
    options.levels = 4;
    vocabulary = bow::Vocabulary::train(training, options);

    camera->fx = camera->fy = 500;
    camera->cx = image.cols / 2.0;
    camera->cy = image.rows / 2.0;
    camera->width = image.cols;
    camera->height = image.rows;
    // Rotation by 15 degrees and scale 0.85 about the centre, then a shift.
    const cv::Mat a = cv::getRotationMatrix2D(cv::Point2f(image.cols / 2.0f, image.rows / 2.0f), 15.0, 0.85);
    homography = cv::Matx33d(a.at<double>(0, 0), a.at<double>(0, 1), a.at<double>(0, 2) + 12.0,  //
                             a.at<double>(1, 0), a.at<double>(1, 1), a.at<double>(1, 2) - 7.0,   //
                             0, 0, 1);
    cv::warpPerspective(image, warped, cv::Mat(homography), image.size());
  }

  std::shared_ptr<map::FrameFeatures> features(const cv::Mat& g) const {
    auto f = std::make_shared<map::FrameFeatures>();
    feature::ORBExtractor().extract(g, 1000, f->keys, f->descriptors);
    f->keys_un = f->keys;
    f->depth_m.assign(f->keys.size(), -1.0f);
    f->right_u.assign(f->keys.size(), -1.0f);
    f->grid = map::FeatureGrid(f->keys_un, camera->undistorted_bounds());
    // Direct index two levels below the root (100 nodes).
    vocabulary.transform(f->descriptors, f->bow, f->bow_features, vocabulary.depth() - 2);
    return f;
  }

  // A keyframe of `g` with a map point on every keypoint whose index passes `with_point`.
  std::shared_ptr<map::KeyFrame> keyframe(const cv::Mat& g, bool (*with_point)(size_t)) {
    auto kf = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), 0, 0.0, camera, levels, features(g),
                                              geometry::SE3::identity());
    map.add_keyframe(kf);
    for (size_t i = 0; i < kf->features->size(); ++i) {
      if (!with_point(i)) continue;
      auto p = std::make_shared<map::MapPoint>(map.next_map_point_id(), geometry::Vec3(0, 0, 1), kf, 0);
      p->add_observation(kf, i);
      kf->add_map_point(i, p);
      map.add_map_point(p);
    }
    return kf;
  }

  // Distance between H * a and b (pixels).
  double transfer_error(const cv::Point2f& a, const cv::Point2f& b) const {
    const cv::Vec3d h = homography * cv::Vec3d(a.x, a.y, 1.0);
    return std::hypot(h[0] / h[2] - b.x, h[1] / h[2] - b.y);
  }
};

bool all(size_t) { return true; }
bool even(size_t i) { return i % 2 == 0; }

TEST_F(BowSearchTest, KeyframeToFrameMatchesAgreeWithTheHomography) {
  const auto kf = keyframe(image, even);
  map::Frame frame(1, 0.0, camera, levels, features(warped));
  std::vector<std::shared_ptr<map::MapPoint>> matches;
  const int n = match::search_by_bow(*kf, frame, matches, 0.7, true);
  ASSERT_EQ(matches.size(), frame.size());
  int counted = 0;
  int consistent = 0;
  std::set<const map::MapPoint*> used;
  for (size_t j = 0; j < matches.size(); ++j) {
    if (!matches[j]) continue;
    ++counted;
    const long i = matches[j]->index_in(kf->id);
    ASSERT_GE(i, 0);
    EXPECT_EQ(i % 2, 0) << "keypoint without a map point was matched";
    EXPECT_TRUE(used.insert(matches[j].get()).second) << "map point matched twice";
    if (transfer_error(kf->features->keys[static_cast<size_t>(i)].pt, frame.features->keys[j].pt) < 4.0) ++consistent;
  }
  EXPECT_EQ(counted, n);
  std::printf("keyframe -> frame: %d matches, %d consistent with the homography\n", n, consistent);
  EXPECT_GE(n, 60);  // half the keypoints have map points
  EXPECT_GE(consistent, 0.9 * n);
}

TEST_F(BowSearchTest, KeyframeToKeyframeMatchesAgreeWithTheHomographyAndUseEachPointOnce) {
  const auto kf1 = keyframe(image, all);
  const auto kf2 = keyframe(warped, all);
  std::vector<std::shared_ptr<map::MapPoint>> matches_12;
  const int n = match::search_by_bow(*kf1, *kf2, matches_12);
  ASSERT_EQ(matches_12.size(), kf1->features->size());
  int consistent = 0;
  int counted = 0;
  std::set<long> used;
  for (size_t i = 0; i < matches_12.size(); ++i) {
    if (!matches_12[i]) continue;
    ++counted;
    const long j = matches_12[i]->index_in(kf2->id);
    ASSERT_GE(j, 0) << "not a point of kf2";
    EXPECT_TRUE(used.insert(j).second) << "kf2 keypoint used twice";
    if (transfer_error(kf1->features->keys[i].pt, kf2->features->keys[static_cast<size_t>(j)].pt) < 4.0) {
      ++consistent;
    }
  }
  EXPECT_EQ(counted, n);
  std::printf("keyframe -> keyframe: %d matches, %d consistent\n", n, consistent);
  EXPECT_GE(n, 100);
  EXPECT_GE(consistent, 0.9 * n);
  // Without map points on kf2 there is nothing to match.
  const auto bare = keyframe(warped, [](size_t) { return false; });
  EXPECT_EQ(match::search_by_bow(*kf1, *bare, matches_12), 0);
  EXPECT_EQ(matches_12.size(), kf1->features->size());
}

TEST_F(BowSearchTest, AnUnrelatedImageGivesFewMatches) {
  const cv::Mat other = gray("baboon.jpg");
  if (other.empty()) GTEST_SKIP() << "baboon.jpg missing";
  const auto kf = keyframe(image, all);
  std::vector<std::shared_ptr<map::MapPoint>> matches;
  const int same = match::search_by_bow(*kf, map::Frame(1, 0.0, camera, levels, features(warped)), matches);
  const int unrelated = match::search_by_bow(*kf, map::Frame(2, 0.0, camera, levels, features(other)), matches);
  std::printf("same scene %d matches, unrelated image %d\n", same, unrelated);
  EXPECT_LT(unrelated, same / 5);
}

}  // namespace
