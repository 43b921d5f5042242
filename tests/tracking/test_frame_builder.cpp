#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "crowdslam/tracking/frame_builder.h"

using namespace crowdslam;

namespace {
cv::Mat textured_image(int w, int h) {
  cv::Mat img(h, w, CV_8UC1);
  std::mt19937 rng(3);
  cv::randu(img, 0, 255);
  cv::GaussianBlur(img, img, cv::Size(5, 5), 1.5);
  return img;
}
std::shared_ptr<geometry::PinholeCamera> camera() {
  auto c = std::make_shared<geometry::PinholeCamera>();
  c->fx = c->fy = 500;
  c->cx = 320;
  c->cy = 240;
  c->width = 640;
  c->height = 480;
  c->bf = 40;
  return c;
}
}  // namespace

TEST(FrameBuilder, DepthGivesVirtualRightCoordinate) {
  tracking::FrameBuilder::Options options;
  options.depth_map_factor = 5000;
  tracking::FrameBuilder builder(camera(), options);
  const cv::Mat gray = textured_image(640, 480);
  // Left half at 2 m, right half without depth.
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(0));
  depth(cv::Rect(0, 0, 320, 480)).setTo(10000);
  feature::RawFeatures raw;
  builder.extract(gray, 800, raw);
  ASSERT_GT(raw.keys.size(), 600u);
  const auto f = builder.assemble(std::move(raw), depth);
  int with_depth = 0;
  for (size_t i = 0; i < f->size(); ++i) {
    const int x = cvRound(f->keys[i].pt.x);
    if (x < 320) {
      ASSERT_FLOAT_EQ(f->depth_m[i], 2.0f);
      ASSERT_NEAR(f->right_u[i], f->keys_un[i].pt.x - 40.0f / 2.0f, 1e-4);
      ++with_depth;
    } else {
      ASSERT_LT(f->depth_m[i], 0.0f);
      ASSERT_LT(f->right_u[i], 0.0f);
      ASSERT_FALSE(f->has_right(i));
    }
  }
  EXPECT_GT(with_depth, 200);
  // The grid finds every keypoint at its own position.
  for (size_t i = 0; i < f->size(); i += 37) {
    const auto found = f->grid.features_in_area(f->keys_un, f->keys_un[i].pt.x, f->keys_un[i].pt.y, 1.0f);
    EXPECT_NE(std::find(found.begin(), found.end(), i), found.end());
  }
}

TEST(FrameBuilder, MonocularHasNoDepth) {
  tracking::FrameBuilder builder(camera(), {});
  feature::RawFeatures raw;
  builder.extract(textured_image(640, 480), 500, raw);
  const auto f = builder.assemble(std::move(raw), cv::Mat());
  ASSERT_GT(f->size(), 300u);
  for (size_t i = 0; i < f->size(); ++i) EXPECT_FALSE(f->has_right(i));
}

TEST(FrameBuilder, BadDepthFactorIsRejected) {
  tracking::FrameBuilder::Options options;
  options.depth_map_factor = 0;
  EXPECT_ANY_THROW(tracking::FrameBuilder(camera(), options));
}
