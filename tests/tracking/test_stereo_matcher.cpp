// Stereo matching on rectified pairs with known disparity: a textured image warped by a disparity field
// (exact sub-pixel ground truth), a pair with a corrupted right region (outlier rejection), a rendered
// synthetic stereo pair against the renderer's depth, and the frame builder's stereo path.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/synth/render.h"
#include "crowdslam/synth/scene.h"
#include "crowdslam/tracking/frame_builder.h"
#include "crowdslam/tracking/stereo_matcher.h"
#include "crowdslam/util/error.h"

using namespace crowdslam;

namespace {
constexpr double kFx = 500.0;
constexpr double kBf = 50.0;  // baseline 0.1 m

// Smooth random texture with corners at several scales.
cv::Mat textured_image(int w, int h, unsigned seed) {
  cv::Mat img(h, w, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 1.2);
  cv::Mat coarse(h / 8, w / 8, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 256);
  cv::resize(coarse, coarse, img.size(), 0, 0, cv::INTER_CUBIC);
  cv::addWeighted(img, 0.6, coarse, 0.4, 0, img);
  return img;
}

// Known disparity (level-0 pixels) at a left pixel: three fronto-parallel planes, sub-pixel values.
float true_disparity(float x) {
  if (x < 213) return 12.35f;  // 4.05 m
  if (x < 426) return 25.7f;   // 1.95 m
  return 40.15f;               // 1.25 m
}

// right(x, y) = left(x + d(x + d), y): every left pixel u appears at u - d in the right image. Planes are
// wide, so d is taken at the right pixel shifted by the plane's own disparity (exact inside each plane).
cv::Mat warp_right(const cv::Mat& left) {
  cv::Mat map_x(left.size(), CV_32F);
  cv::Mat map_y(left.size(), CV_32F);
  for (int y = 0; y < left.rows; ++y) {
    for (int x = 0; x < left.cols; ++x) {
      float d = true_disparity(static_cast<float>(x) + 40.0f);
      for (int it = 0; it < 3; ++it) d = true_disparity(static_cast<float>(x) + d);
      map_x.at<float>(y, x) = static_cast<float>(x) + d;
      map_y.at<float>(y, x) = static_cast<float>(y);
    }
  }
  cv::Mat right;
  cv::remap(left, right, map_x, map_y, cv::INTER_CUBIC, cv::BORDER_REFLECT_101);
  return right;
}

struct Extracted {
  std::vector<cv::KeyPoint> keys;
  cv::Mat descriptors;
  std::vector<cv::Mat> pyramid;
};

Extracted extract(const cv::Mat& image, int features) {
  feature::ORBExtractor extractor;
  Extracted e;
  extractor.extract(image, features, e.keys, e.descriptors);
  for (const auto& level : extractor.pyramid()) e.pyramid.push_back(level.clone());
  return e;
}

tracking::StereoMatches match(const Extracted& l, const Extracted& r, const tracking::StereoMatcherOptions& o = {}) {
  tracking::StereoMatcher matcher(o, map::ScaleLevels(1.2f, 8), kBf, kFx);
  tracking::StereoMatches out;
  matcher.match({l.keys, l.descriptors, l.pyramid}, {r.keys, r.descriptors, r.pyramid}, out);
  return out;
}

// Away from the plane borders (where the true disparity of a window is mixed).
bool near_border(float x) { return std::abs(x - 213) < 25 || std::abs(x - 426) < 25; }
}  // namespace

namespace {
// Sorted absolute disparity errors of the matched interior keypoints; `interior` counts all of them.
std::vector<double> disparity_errors(const Extracted& l, const tracking::StereoMatches& m, int& interior) {
  std::vector<double> errors;
  interior = 0;
  for (size_t i = 0; i < l.keys.size(); ++i) {
    const float x = l.keys[i].pt.x;
    if (near_border(x) || x < 60) continue;  // leftmost columns: the point falls outside the right image
    ++interior;
    if (m.depth_m[i] <= 0) continue;
    const double disparity = x - m.right_u[i];
    EXPECT_NEAR(m.depth_m[i], kBf / disparity, 1e-3 * m.depth_m[i]);
    errors.push_back(std::abs(disparity - true_disparity(x)));
  }
  std::sort(errors.begin(), errors.end());
  return errors;
}
}  // namespace

TEST(StereoMatcher, RecoversKnownSubPixelDisparity) {
  const cv::Mat left = textured_image(640, 480, 7);
  const cv::Mat right = warp_right(left);
  const Extracted l = extract(left, 1000);
  const Extracted r = extract(right, 1000);
  const auto m = match(l, r);
  ASSERT_EQ(m.depth_m.size(), l.keys.size());
  EXPECT_EQ(m.matched, m.refined - m.outliers);
  EXPECT_GT(m.descriptor_matches, 400);  // limited by keypoint repeatability between the two images

  int interior = 0;
  const std::vector<double> errors = disparity_errors(l, m, interior);
  ASSERT_GT(interior, 500);
  // Of the matches, none is far off, and the median is a small fraction of a pixel (0.035 measured).
  EXPECT_GT(static_cast<double>(errors.size()), 0.45 * interior);
  EXPECT_LT(errors[errors.size() / 2], 0.06);
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.2);
  EXPECT_LT(errors.back(), 1.0);

  // The parabola through SAD costs is biased towards whole pixels: clearly worse than through SSD.
  tracking::StereoMatcherOptions sad_fit;
  sad_fit.parabola_on_ssd = false;
  int unused = 0;
  const std::vector<double> sad_errors = disparity_errors(l, match(l, r, sad_fit), unused);
  ASSERT_GT(sad_errors.size(), errors.size() * 9 / 10);
  EXPECT_GT(sad_errors[sad_errors.size() / 2], 1.5 * errors[errors.size() / 2]);
}

TEST(StereoMatcher, RejectsMatchesWhoseWindowsDisagree) {
  const cv::Mat left = textured_image(640, 480, 11);
  cv::Mat right = warp_right(left);
  // The right image's middle band is replaced by other texture, but the right keypoints and descriptors
  // are the left ones moved by the true disparity: every descriptor matches, the pixels do not.
  const cv::Rect corrupted(200, 0, 260, 480);
  textured_image(640, 480, 99)(corrupted).copyTo(right(corrupted));
  Extracted l = extract(left, 1000);
  Extracted r = extract(right, 1000);
  r.keys = l.keys;
  r.descriptors = l.descriptors.clone();
  for (auto& k : r.keys) k.pt.x -= true_disparity(k.pt.x);
  const auto m = match(l, r);

  int clean = 0, clean_matched = 0, bad = 0, bad_matched = 0;
  for (size_t i = 0; i < l.keys.size(); ++i) {
    const float x = l.keys[i].pt.x;
    const float x_right = x - true_disparity(x);
    // The window (11 px at level 0, up to 11 * 1.2^7 px at the top level) plus the search range.
    const float reach = 10.0f * std::pow(1.2f, static_cast<float>(l.keys[i].octave)) + 3.0f;
    if (x_right > corrupted.x + reach && x_right < corrupted.br().x - reach) {
      ++bad;
      if (m.depth_m[i] > 0) ++bad_matched;
    } else if ((x_right < corrupted.x - reach || x_right > corrupted.br().x + reach) && !near_border(x) && x > 60) {
      ++clean;
      if (m.depth_m[i] > 0) ++clean_matched;
    }
  }
  ASSERT_GT(bad, 100);
  ASSERT_GT(clean, 200);
  EXPECT_EQ(m.descriptor_matches, static_cast<int>(l.keys.size()));  // each finds its own copy
  EXPECT_GT(m.outliers + (m.descriptor_matches - m.refined), bad * 9 / 10);
  EXPECT_LT(bad_matched, bad / 20 + 1);  // all but a few (windows on flat texture) rejected
  EXPECT_GT(clean_matched, clean * 8 / 10);
  // Without the statistics test more of the corrupted band survives.
  tracking::StereoMatcherOptions loose;
  loose.outlier_factor = 1e6;
  const auto unfiltered = match(l, r, loose);
  EXPECT_EQ(unfiltered.outliers, 0);
  EXPECT_GT(unfiltered.matched, m.matched);
}

TEST(StereoMatcher, OnlySearchesTheDisparityRange) {
  const cv::Mat left = textured_image(640, 480, 7);
  const Extracted l = extract(left, 800);
  const Extracted r = extract(warp_right(left), 800);
  // Nearest depth 2.5 m: max disparity 20 px, so only the far plane (12.35 px) can match.
  tracking::StereoMatcherOptions near_limit;
  near_limit.min_depth_m = 2.5;
  const auto m = match(l, r, near_limit);
  int far = 0;
  for (size_t i = 0; i < l.keys.size(); ++i) {
    if (m.depth_m[i] <= 0) continue;
    EXPECT_GE(m.depth_m[i], 2.5f * 0.999f);
    if (l.keys[i].pt.x < 200) ++far;
  }
  EXPECT_GT(far, 100);
  EXPECT_LT(m.matched, far + 20);
}

TEST(StereoMatcher, BadOptionsAreRejected) {
  tracking::StereoMatcherOptions o;
  o.sad_half_window = 0;
  EXPECT_THROW(o.check(), InputError);
  o = {};
  o.outlier_factor = 0;
  EXPECT_THROW(o.check(), InputError);
  EXPECT_THROW(tracking::StereoMatcher({}, map::ScaleLevels(), 0.0, kFx), InputError);
}

TEST(StereoMatcher, RenderedStereoPairDepthMatchesTheRenderer) {
  synth::SynthOptions options;
  options.frames = 2;
  options.width = 640;
  options.height = 480;
  const synth::Scene scene = synth::Scene::build(options);
  const synth::RenderedFrame left = synth::render_frame(scene, 0, false);
  const synth::RenderedFrame right = synth::render_frame(scene, 0, true);
  auto camera = std::make_shared<geometry::PinholeCamera>();
  const auto& k = scene.intrinsics();
  camera->fx = k.fx;
  camera->fy = k.fy;
  camera->cx = k.cx;
  camera->cy = k.cy;
  camera->width = k.width;
  camera->height = k.height;
  camera->bf = k.fx * synth::kStereoBaselineM;
  tracking::FrameBuilder builder(camera, {});
  cv::Mat left_gray, right_gray;
  cv::cvtColor(left.colour, left_gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(right.colour, right_gray, cv::COLOR_BGR2GRAY);
  feature::RawFeatures raw_left, raw_right;
  builder.extract(left_gray, 1000, raw_left);
  builder.extract_right(right_gray, 1000, raw_right);
  const auto f = builder.assemble_stereo(std::move(raw_left), raw_right);

  std::vector<double> relative;
  int with_depth = 0;
  for (size_t i = 0; i < f->size(); ++i) {
    if (f->depth_m[i] <= 0) {
      EXPECT_FALSE(f->has_right(i));
      continue;
    }
    ++with_depth;
    EXPECT_NEAR(f->right_u[i], f->keys_un[i].pt.x - camera->bf / f->depth_m[i], 1e-3);
    // Ground truth: the renderer's depth; skip keypoints on a depth edge (3x3 neighbourhood varies).
    const int x = cvRound(f->keys[i].pt.x);
    const int y = cvRound(f->keys[i].pt.y);
    double lo = 1e9, hi = 0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const float d = left.depth_m.at<float>(std::clamp(y + dy, 0, 479), std::clamp(x + dx, 0, 639));
        lo = std::min<double>(lo, d);
        hi = std::max<double>(hi, d);
      }
    if (lo <= 0 || hi > 1.05 * lo) continue;
    relative.push_back(std::abs(f->depth_m[i] - left.depth_m.at<float>(y, x)) / left.depth_m.at<float>(y, x));
  }
  EXPECT_EQ(with_depth, builder.last_stereo_matches().matched);
  ASSERT_GT(relative.size(), 300u);
  std::sort(relative.begin(), relative.end());
  EXPECT_LT(relative[relative.size() / 2], 0.01);
  EXPECT_LT(relative[relative.size() * 9 / 10], 0.03);
}

TEST(StereoMatcher, FrameBuilderRejectsUnrectifiedCameraAndMismatchedSizes) {
  auto camera = std::make_shared<geometry::PinholeCamera>();
  camera->fx = camera->fy = kFx;
  camera->cx = 320;
  camera->cy = 240;
  camera->width = 640;
  camera->height = 480;
  camera->bf = kBf;
  {
    tracking::FrameBuilder builder(camera, {});
    feature::RawFeatures l, r;
    builder.extract(textured_image(640, 480, 1), 300, l);
    builder.extract_right(textured_image(320, 240, 2), 300, r);
    EXPECT_THROW((void)builder.assemble_stereo(std::move(l), r), InputError);
  }
  camera->distortion.k1 = -0.2;
  tracking::FrameBuilder builder(camera, {});
  feature::RawFeatures l, r;
  builder.extract(textured_image(640, 480, 1), 300, l);
  builder.extract_right(textured_image(640, 480, 2), 300, r);
  EXPECT_THROW((void)builder.assemble_stereo(std::move(l), r), InputError);
}
