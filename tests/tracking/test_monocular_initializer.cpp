// Monocular initialisation on frames rendered by the synthetic generator, against its exact poses and
// depths: the two-view geometry (up to scale), the initial map (median depth 1, consistent scale), and
// the cases that must not initialise (static camera, pure rotation, textureless images).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "crowdslam/map/map.h"
#include "crowdslam/map/map_point.h"
#include "crowdslam/synth/render.h"
#include "crowdslam/synth/scene.h"
#include "crowdslam/tracking/frame_builder.h"
#include "crowdslam/tracking/monocular_initializer.h"
#include "crowdslam/util/error.h"

using namespace crowdslam;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

class MonocularInit : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    synth::SynthOptions options;
    options.frames = 300;  // the default loop; only the first frames are rendered
    scene_ = new synth::Scene(synth::Scene::build(options));
  }
  static void TearDownTestSuite() {
    delete scene_;
    scene_ = nullptr;
  }

  MonocularInit() {
    const auto& k = scene_->intrinsics();
    camera_ = std::make_shared<geometry::PinholeCamera>();
    camera_->fx = k.fx;
    camera_->fy = k.fy;
    camera_->cx = k.cx;
    camera_->cy = k.cy;
    camera_->width = k.width;
    camera_->height = k.height;
    builder_ = std::make_unique<tracking::FrameBuilder>(camera_, tracking::FrameBuilder::Options{});
  }

  // A frame (2000 features, as during initialisation) from an image.
  map::Frame make_frame(uint64_t id, const cv::Mat& colour) {
    cv::Mat gray;
    cv::cvtColor(colour, gray, cv::COLOR_BGR2GRAY);
    feature::RawFeatures raw;
    builder_->extract(gray, 2000, raw);
    return map::Frame(id, static_cast<double>(id), camera_, builder_->levels(),
                      builder_->assemble(std::move(raw), {}));
  }

  static geometry::SE3 world_from_cam(int frame) {
    return scene_->trajectory()[static_cast<size_t>(frame)].world_from_cam;
  }

  static synth::Scene* scene_;
  std::shared_ptr<geometry::PinholeCamera> camera_;
  std::unique_ptr<tracking::FrameBuilder> builder_;
};
synth::Scene* MonocularInit::scene_ = nullptr;

double rotation_error_deg(const geometry::SE3& a, const geometry::SE3& b) {
  return geometry::rotation_angle(a.rotation_matrix().transpose() * b.rotation_matrix()) / kDeg;
}

double direction_error_deg(const geometry::Vec3& a, const geometry::Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) / kDeg;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

// Renderer depth at a keypoint's (distorted = undistorted here) pixel.
float true_depth(const synth::RenderedFrame& frame, const cv::Point2f& px) {
  return frame.depth_m.at<float>(cvRound(px.y), cvRound(px.x));
}

TEST_F(MonocularInit, InitialisesEarlyOnTheLoopAndBuildsAMapAtMedianDepthOne) {
  tracking::MonocularInitializer initializer;
  const synth::RenderedFrame first = synth::render_frame(*scene_, 0);
  EXPECT_FALSE(initializer.add_frame(make_frame(0, first.colour)).has_value());
  ASSERT_TRUE(initializer.has_reference());

  std::optional<tracking::TwoViewInitialization> init;
  std::optional<map::Frame> current;
  int frame = 1;
  for (; frame <= 30 && !init; ++frame) {
    current.emplace(make_frame(static_cast<uint64_t>(frame), synth::render_frame(*scene_, frame).colour));
    init = initializer.add_frame(*current);
  }
  ASSERT_TRUE(init.has_value()) << "no initialisation within 30 frames";
  const int init_frame = frame - 1;
  EXPECT_EQ(init->reference->id, 0u);
  EXPECT_GE(init->parallax_deg, 1.0);
  EXPECT_GE(init->matches.size(), 100u);

  // Two-view geometry at this first, small baseline (parallax just above 1 degree): the rotation is
  // accurate, the translation direction only roughly (rotation and sideways motion look alike).
  const geometry::SE3 truth = world_from_cam(init_frame).inverse() * world_from_cam(0);
  EXPECT_LT(rotation_error_deg(init->current_from_reference, truth), 0.5);
  EXPECT_LT(direction_error_deg(init->current_from_reference.translation(), truth.translation()), 6.0);

  // The initial map: two keyframes, median depth 1, the second pose = true pose at the map's scale.
  map::Map map;
  const auto keyframes = tracking::build_initial_map(map, *init, *current, initializer.options());
  ASSERT_TRUE(keyframes.has_value());
  const auto& [kf1, kf2] = *keyframes;
  EXPECT_EQ(map.num_keyframes(), 2u);
  EXPECT_EQ(kf2->parent(), kf1);
  EXPECT_NEAR(kf1->scene_median_depth(), 1.0, 1e-5);
  EXPECT_GE(kf2->tracked_map_points(1), 100);
  // Metres per map unit from the renderer's depth at the first keyframe's points; the points' depths
  // at that scale agree with the renderer's.
  std::vector<double> true_depths;
  std::vector<std::pair<double, double>> depth_pairs;  // (map depth, true depth)
  for (const auto& p : kf1->valid_map_points()) {
    const long index = p->index_in(kf1->id);
    const float depth = true_depth(first, kf1->features->keys[static_cast<size_t>(index)].pt);
    if (depth <= 0) continue;
    true_depths.push_back(depth);
    depth_pairs.emplace_back((kf1->cam_from_world() * p->world()).z(), depth);
  }
  const double map_scale = median(true_depths);
  std::vector<double> relative;
  for (const auto& [d, t] : depth_pairs) relative.push_back(std::abs(d * map_scale - t) / t);
  EXPECT_LT(median(relative), 0.05);
  const geometry::SE3 pose2 = kf2->cam_from_world();
  EXPECT_LT(rotation_error_deg(pose2, truth), 0.5);
  EXPECT_LT(direction_error_deg(pose2.translation(), truth.translation()), 5.0);
  EXPECT_NEAR(pose2.translation().norm() * map_scale, truth.translation().norm(),
              0.05 * truth.translation().norm());
  // The current frame is the second keyframe, with its matches.
  ASSERT_TRUE(current->cam_from_world.has_value());
  EXPECT_LT((current->cam_from_world->translation() - pose2.translation()).norm(), 1e-12);
  int slots = 0;
  for (const auto& p : current->map_points) slots += p != nullptr;
  EXPECT_EQ(slots, kf2->tracked_map_points(1));
}

TEST_F(MonocularInit, WiderBaselineRecoversPoseAndDepthsUpToScale) {
  // Frames 0 and 6 of the loop (about 7 degrees of rotation and 11 cm of translation).
  tracking::MonocularInitializer initializer;
  const synth::RenderedFrame first = synth::render_frame(*scene_, 0);
  initializer.add_frame(make_frame(0, first.colour));
  map::Frame current = make_frame(6, synth::render_frame(*scene_, 6).colour);
  const auto init = initializer.add_frame(current);
  ASSERT_TRUE(init.has_value());
  const geometry::SE3 truth = world_from_cam(6).inverse() * world_from_cam(0);
  EXPECT_LT(rotation_error_deg(init->current_from_reference, truth), 0.5);
  EXPECT_LT(direction_error_deg(init->current_from_reference.translation(), truth.translation()), 2.0);
  // Triangulated depths against the renderer's: one common scale (their median ratio) explains them
  // within a few percent, and it is the baseline ratio |t_true| / |t_est|.
  std::vector<double> ratios;
  for (const auto& m : init->matches) {
    const float depth = true_depth(first, init->reference->features->keys[m.reference_index].pt);
    if (depth > 0) ratios.push_back(depth / m.point_reference.z());
  }
  ASSERT_GT(ratios.size(), 100u);
  const double scale = median(ratios);
  std::vector<double> relative;
  for (double r : ratios) relative.push_back(std::abs(r / scale - 1.0));
  EXPECT_LT(median(relative), 0.03);
  const double baseline_ratio =
      truth.translation().norm() / init->current_from_reference.translation().norm();
  EXPECT_NEAR(scale, baseline_ratio, 0.05 * baseline_ratio);
}

TEST_F(MonocularInit, StaticCameraAndPureRotationNeverInitialise) {
  // Static camera: same image again and again (all matches, no parallax).
  tracking::MonocularInitializer initializer;
  const cv::Mat image = synth::render_frame(*scene_, 0).colour;
  for (uint64_t id = 0; id < 4; ++id) EXPECT_FALSE(initializer.add_frame(make_frame(id, image)).has_value());
  EXPECT_GT(initializer.last_num_matches(), 100);  // matched, but not initialised
  EXPECT_EQ(initializer.reference()->id, 0u);      // and the reference is kept

  // Pure rotation about the camera centre (up to 6 degrees of pan): a homography without parallax.
  initializer.reset();
  const geometry::SE3 start = world_from_cam(0);
  for (int k = 0; k <= 6; ++k) {
    const geometry::SE3 pan(Eigen::Quaterniond(Eigen::AngleAxisd(k * 1.0 * kDeg, geometry::Vec3::UnitY())),
                            geometry::Vec3::Zero());
    const auto rendered = synth::render(*scene_, start * pan, {});
    EXPECT_FALSE(
        initializer.add_frame(make_frame(static_cast<uint64_t>(10 + k), rendered.colour)).has_value())
        << "rotation " << k << " deg";
  }
  EXPECT_GT(initializer.last_num_matches(), 100);
}

TEST_F(MonocularInit, TexturelessFramesNeverBecomeTheReference) {
  tracking::MonocularInitializer initializer;
  const cv::Mat blank(480, 640, CV_8UC3, cv::Scalar(128, 128, 128));
  for (uint64_t id = 0; id < 3; ++id) {
    EXPECT_FALSE(initializer.add_frame(make_frame(id, blank)).has_value());
    EXPECT_FALSE(initializer.has_reference());
  }
  // A textured frame becomes the reference; a textureless one after it drops it.
  initializer.add_frame(make_frame(3, synth::render_frame(*scene_, 0).colour));
  EXPECT_TRUE(initializer.has_reference());
  initializer.add_frame(make_frame(4, blank));
  EXPECT_FALSE(initializer.has_reference());
}

TEST(MonocularInitOptions, CheckNamesTheBadValue) {
  tracking::MonocularInitializerOptions options;
  EXPECT_NO_THROW(options.check());
  options.min_matches = 3;
  try {
    options.check();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("min_matches"), std::string::npos);
  }
  options = {};
  options.two_view.min_parallax_deg = -1;
  EXPECT_THROW(tracking::MonocularInitializer{options}, InputError);
}

// Monocular re-anchoring (InitialMapPlacement): into a map that already holds a keyframe, the reference
// frame goes where the placement says and the map is scaled to the predicted baseline (here the true
// pose and baseline: the two-view map then lands on the true geometry); with a baseline too small to
// measure, to the expected median depth.
TEST_F(MonocularInit, APlacedMapLandsWhereTheMotionSaysAtItsScale) {
  tracking::MonocularInitializer initializer;
  const synth::RenderedFrame first = synth::render_frame(*scene_, 0);
  initializer.add_frame(make_frame(0, first.colour));
  map::Frame current = make_frame(6, synth::render_frame(*scene_, 6).colour);
  const auto init = initializer.add_frame(current);
  ASSERT_TRUE(init.has_value());
  map::Map map;
  const auto existing = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), 99, 0.0, current.camera,
                                                        current.levels, current.features, geometry::SE3());
  map.add_keyframe(existing);

  const geometry::SE3 reference_pose = world_from_cam(0).inverse();
  const geometry::SE3 current_pose = world_from_cam(6).inverse();
  tracking::InitialMapPlacement placement;
  placement.reference_cam_from_world = reference_pose;
  placement.predicted_baseline = (world_from_cam(6).translation() - world_from_cam(0).translation()).norm();
  placement.expected_median_depth = 2.0;
  placement.parent = existing;
  const auto keyframes = tracking::build_initial_map(map, *init, current, initializer.options(), &placement);
  ASSERT_TRUE(keyframes.has_value());
  EXPECT_TRUE(placement.scaled_by_baseline);
  EXPECT_EQ(map.num_keyframes(), 3u);
  const auto& [kf1, kf2] = *keyframes;
  EXPECT_EQ(kf1->parent(), existing);  // one spanning tree, no parent cycle between the two
  EXPECT_EQ(kf2->parent(), kf1);
  EXPECT_LT((kf1->cam_from_world().translation() - reference_pose.translation()).norm(), 1e-9);
  EXPECT_LT(rotation_error_deg(kf2->cam_from_world(), current_pose), 0.5);
  const double centre_error = (kf2->world_from_cam().translation() - world_from_cam(6).translation()).norm();
  EXPECT_LT(centre_error, 0.1 * placement.predicted_baseline);
  // The points at the renderer's depths, in metres.
  std::vector<double> relative;
  for (const auto& p : kf1->valid_map_points()) {
    const float depth = true_depth(first, kf1->features->keys[static_cast<size_t>(p->index_in(kf1->id))].pt);
    if (depth > 0) relative.push_back(std::abs((kf1->cam_from_world() * p->world()).z() - depth) / depth);
  }
  ASSERT_GT(relative.size(), 50u);
  EXPECT_LT(median(relative), 0.05);

  // A baseline of 1 % of the expected depth is not measured: the median depth sets the scale.
  map::Map other;
  map::Frame again = make_frame(6, synth::render_frame(*scene_, 6).colour);
  placement.predicted_baseline = 0.01 * placement.expected_median_depth;
  placement.parent = nullptr;
  ASSERT_TRUE(tracking::build_initial_map(other, *init, again, initializer.options(), &placement).has_value());
  EXPECT_FALSE(placement.scaled_by_baseline);
  EXPECT_NEAR(other.keyframes().front()->scene_median_depth(), 2.0, 1e-3);
}

// A wall filling the view while the camera turns and moves sideways (a re-anchoring where people left
// only a wall): the homography's two decompositions explain every match, so the two views alone do not
// initialise; with the motion's prediction as the prior they do, at the true relative pose, and a prior
// that disagrees with both decompositions keeps them from it.
TEST_F(MonocularInit, AMotionPriorInitialisesOnAWallAndAWrongOneDoesNot) {
  // 1.5 m in front of the -y wall (y = -2.5), looking at it: camera z = -y, y = -z (down), x = -x.
  geometry::Mat3 r;
  r << -1, 0, 0, 0, 0, -1, 0, -1, 0;
  const geometry::SE3 first_pose(Eigen::Quaterniond(r), geometry::Vec3(0.0, -1.0, 1.5));
  // 10 degrees of pan about the camera's vertical and 15 cm to the side, 5 cm back.
  const geometry::SE3 motion(Eigen::Quaterniond(Eigen::AngleAxisd(10.0 * kDeg, geometry::Vec3::UnitY())),
                             geometry::Vec3(-0.15, 0.0, -0.05));
  const geometry::SE3 second_pose = first_pose * motion;  // world_from_cam
  const geometry::SE3 truth = second_pose.inverse() * first_pose;  // cam2_from_cam1
  const cv::Mat first = synth::render(*scene_, first_pose, {}).colour;
  const cv::Mat second = synth::render(*scene_, second_pose, {}).colour;

  tracking::MonocularInitializer alone;
  alone.add_frame(make_frame(0, first));
  EXPECT_FALSE(alone.add_frame(make_frame(1, second)).has_value());
  EXPECT_GT(alone.last_num_matches(), 100);  // matched, but ambiguous

  // The prior as a motion model gives it: 2 degrees and 15 degrees of travel direction off, another scale.
  tracking::MonocularInitializer with_prior;
  geometry::TwoViewPrior prior;
  prior.cam2_from_cam1 =
      geometry::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(2.0 * kDeg, geometry::Vec3::UnitY())) * truth.rotation(),
                    Eigen::AngleAxisd(15.0 * kDeg, geometry::Vec3::UnitY()) * truth.translation() * 0.3);
  with_prior.set_prior([&](double reference_s, double current_s) {
    EXPECT_EQ(reference_s, 0.0);  // the two frames' timestamps
    EXPECT_EQ(current_s, 1.0);
    return std::optional<geometry::TwoViewPrior>(prior);
  });
  with_prior.add_frame(make_frame(0, first));
  const auto init = with_prior.add_frame(make_frame(1, second));
  ASSERT_TRUE(init.has_value());
  EXPECT_EQ(init->model, geometry::TwoViewModel::kHomography);
  EXPECT_LT(rotation_error_deg(init->current_from_reference, truth), 0.5);
  EXPECT_LT(direction_error_deg(init->current_from_reference.translation(), truth.translation()), 3.0);

  // Turning the other way: no decomposition agrees, no initialisation (and none after reset() either:
  // the prior stays until clear_prior()).
  prior.cam2_from_cam1 = geometry::SE3(truth.rotation().inverse(), -truth.translation());
  with_prior.reset();
  with_prior.add_frame(make_frame(0, first));
  EXPECT_FALSE(with_prior.add_frame(make_frame(1, second)).has_value());
  with_prior.clear_prior();
  with_prior.reset();
  with_prior.add_frame(make_frame(0, first));
  EXPECT_FALSE(with_prior.add_frame(make_frame(1, second)).has_value());  // ambiguous again
}
