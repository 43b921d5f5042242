// Billboard people (person sprites): where they are drawn, occlusion, the person mask and people_gt.txt,
// determinism, and the box fallback without sprites.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "crowdslam/synth/render.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/util/text.h"
#include "synth_test_util.h"
#include "test_support.h"

namespace crowdslam::synth {
namespace {
namespace fs = std::filesystem;
using crowdslam::test::read_text;
using crowdslam::test::TempDir;
using V3 = Eigen::Vector3d;

SynthOptions sprite_options(const fs::path& sprites, int people, int frames,
                            TrajectoryKind trajectory = TrajectoryKind::kLoop) {
  SynthOptions o;
  o.trajectory = trajectory;
  o.width = 160;
  o.height = 120;
  o.frames = frames;
  o.people = people;
  o.seed = 3;
  o.texture_dir = "";  // procedural textures: fast
  o.sprite_dir = sprites.string();
  return o;
}

// The line trajectory's frame 90: at (0, -0.4, 1.4) looking at the +y wall 2.9 m away, the cabinet
// (y >= 2.1) in front of it; the floor is in view from about 2.2 m on.
constexpr int kFrame = 90;

// A billboard `distance` metres straight ahead of the camera (horizontally), `right` metres to its right.
Billboard ahead(const Scene& scene, const geometry::SE3& pose, double distance, double right, int sprite,
                int id) {
  const V3 c = pose.translation();
  const Eigen::Vector2d f =
      Eigen::Vector2d(pose.rotation_matrix()(0, 2), pose.rotation_matrix()(1, 2)).normalized();
  const Eigen::Vector2d r(f.y(), -f.x());
  Billboard b =
      facing_billboard(c.head<2>() + distance * f + right * r, c, 1.7, scene.sprites()[sprite].aspect());
  b.sprite = sprite;
  b.person_id = id;
  return b;
}

int count_label(const cv::Mat& label, int id) { return cv::countNonZero(label == id); }

// Pixel of a world point (rounded), and its depth.
cv::Point pixel_of(const V3& world, const geometry::SE3& pose, const Intrinsics& k, double* depth = nullptr) {
  const V3 p = pose.inverse() * world;
  if (depth) *depth = p.z();
  return {static_cast<int>(std::lround(k.fx * p.x() / p.z() + k.cx)),
          static_cast<int>(std::lround(k.fy * p.y() / p.z() + k.cy))};
}

// A point on the billboard at fractions across (from its left edge) and down (from its top).
V3 on_billboard(const Billboard& b, double across, double down) {
  return b.foot + (across - 0.5) * b.width_m * V3(b.axis.x(), b.axis.y(), 0.0) +
         V3(0, 0, (1.0 - down) * b.height_m);
}

TEST(SynthBillboard, DrawnWhereProjectedWithItsLabelAndDepthAndSeenThroughWhereTransparent) {
  TempDir tmp;
  test::write_test_sprites(tmp / "s", 2);
  const Scene scene = Scene::build(sprite_options(tmp / "s", 0, 100, TrajectoryKind::kLine));
  const Intrinsics& k = scene.intrinsics();
  const geometry::SE3 pose = scene.trajectory()[kFrame].world_from_cam;
  const Billboard b = ahead(scene, pose, 2.4, 0.0, 0, 7);
  const RenderedFrame empty = render(scene, pose, {});
  const RenderedFrame r = render(scene, pose, {}, {b});
  // Closed form: the torso's middle is the person, at the depth of its point; between the legs is the room.
  double depth = 0.0;
  const cv::Point torso = pixel_of(on_billboard(b, 0.5, 60.5 / 160.0), pose, k, &depth);
  ASSERT_TRUE(cv::Rect(0, 0, k.width, k.height).contains(torso));
  EXPECT_EQ(r.person_label.at<std::uint16_t>(torso), 7);
  EXPECT_EQ(r.moving.at<std::uint8_t>(torso), 255);
  EXPECT_NEAR(r.depth_m.at<float>(torso), depth, 0.01);  // the pixel's centre is within half a pixel
  const cv::Point gap = pixel_of(on_billboard(b, 0.5, 130.5 / 160.0), pose, k);
  ASSERT_TRUE(cv::Rect(0, 0, k.width, k.height).contains(gap));
  EXPECT_EQ(r.person_label.at<std::uint16_t>(gap), 0);
  EXPECT_EQ(r.depth_m.at<float>(gap), empty.depth_m.at<float>(gap));
  EXPECT_EQ(r.colour.at<cv::Vec3b>(gap), empty.colour.at<cv::Vec3b>(gap));
  // Every pixel: labelled exactly where its ray meets the quad in an opaque texel; there the depth is the
  // hit's, elsewhere the image is the empty room's.
  const Sprite& sprite = scene.sprites()[0];
  int labelled = 0;
  int disagree = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const V3 dir = pose.rotation_matrix() * V3((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      const auto hit = intersect_quad(b, pose.translation(), dir);
      const bool expected = hit && sprite.opaque(hit->across * 60 - 0.5, hit->down * 160 - 0.5) &&
                            hit->t < empty.depth_m.at<float>(v, u);
      const bool is_person = r.person_label.at<std::uint16_t>(v, u) == 7;
      disagree += expected != is_person;
      if (is_person) {
        ++labelled;
        EXPECT_NEAR(r.depth_m.at<float>(v, u), hit ? hit->t : 0.0, 1e-5);
      } else {
        EXPECT_EQ(r.depth_m.at<float>(v, u), empty.depth_m.at<float>(v, u));
      }
    }
  }
  EXPECT_LE(disagree, 2);
  // 1.7 m at 2.4 m: ~90 rows; the person shape fills ~60 % of its 0.64 m wide quad (~35 columns).
  EXPECT_GT(labelled, 1500);
  // Nothing in front: the footprint is exactly the labelled pixels, and its extent theirs.
  const BillboardFootprint f = billboard_footprint(scene, b, pose);
  EXPECT_EQ(f.pixels, labelled);
  cv::Mat mine = r.person_label == 7;
  const cv::Rect extent = cv::boundingRect(mine);
  EXPECT_EQ(f.min_u, extent.x);
  EXPECT_EQ(f.max_u, extent.x + extent.width - 1);
  EXPECT_EQ(f.min_v, extent.y);
  EXPECT_EQ(f.max_v, extent.y + extent.height - 1);
  EXPECT_GE(f.unbounded_pixels, f.pixels);
  EXPECT_LT(f.unbounded_pixels, 1.03 * f.pixels) << "all of it but the feet is in the image";
  // Half beyond the left border (its middle projects onto it): half its pixels count, the other half is
  // what MOT's visibility misses beyond the border.
  const double to_border = -(k.cx + 0.5) / k.fx * 2.4;
  const BillboardFootprint half = billboard_footprint(scene, ahead(scene, pose, 2.4, to_border, 0, 7), pose);
  EXPECT_GT(half.pixels, 0);
  EXPECT_NEAR(half.unbounded_pixels / half.pixels, 2.0, 0.3);
  // The whole person, as far as when centred (a little larger off the axis, on a flat image plane).
  EXPECT_NEAR(half.unbounded_pixels, f.unbounded_pixels, 0.25 * f.unbounded_pixels);
  // Mirrored: the same pixel count, the image flipped about the billboard's middle.
  Billboard m = b;
  m.mirrored = true;
  EXPECT_EQ(billboard_footprint(scene, m, pose).pixels, f.pixels);
}

TEST(SynthBillboard, APersonBehindAnotherIsPartlyVisibleAndAloneFully) {
  TempDir tmp;
  test::write_test_sprites(tmp / "s", 2);
  const Scene scene = Scene::build(sprite_options(tmp / "s", 0, 100, TrajectoryKind::kLine));
  const geometry::SE3 pose = scene.trajectory()[kFrame].world_from_cam;
  const Billboard front = ahead(scene, pose, 1.1, 0.0, 0, 1);
  const Billboard back = ahead(scene, pose, 2.0, 0.15, 1, 2);
  const RenderedFrame both = render(scene, pose, {}, {back, front});
  const RenderedFrame alone = render(scene, pose, {}, {back});
  const BillboardFootprint f_back = billboard_footprint(scene, back, pose);
  const BillboardFootprint f_front = billboard_footprint(scene, front, pose);
  EXPECT_EQ(count_label(both.person_label, 1), f_front.pixels) << "nothing in front of the front person";
  EXPECT_EQ(count_label(alone.person_label, 2), f_back.pixels)
      << "alone, the back person shows all its pixels";
  const int visible = count_label(both.person_label, 2);
  EXPECT_GT(visible, 0) << "seen beside and through the gaps of the front person";
  EXPECT_LT(visible, 0.8 * f_back.pixels);
  // Its visible pixels are pixels of its footprint, and the front person is nearer wherever it shows.
  for (int v = 0; v < both.person_label.rows; ++v) {
    for (int u = 0; u < both.person_label.cols; ++u) {
      if (both.person_label.at<std::uint16_t>(v, u) == 2) {
        ASSERT_EQ(alone.person_label.at<std::uint16_t>(v, u), 2);
        ASSERT_EQ(both.depth_m.at<float>(v, u), alone.depth_m.at<float>(v, u));
      }
      if (both.person_label.at<std::uint16_t>(v, u) == 1 && alone.person_label.at<std::uint16_t>(v, u) == 2) {
        ASSERT_LT(both.depth_m.at<float>(v, u), alone.depth_m.at<float>(v, u));
      }
    }
  }
}

// Data lines of people_gt.txt by frame (1-based): id -> fields.
std::map<int, std::map<int, std::vector<std::string>>> gt_by_frame(const fs::path& file) {
  std::map<int, std::map<int, std::vector<std::string>>> out;
  for (const std::string& line : read_lines(file.string())) {
    const auto f = split_fields(line);
    out[std::stoi(f[0])][std::stoi(f[1])] = f;
  }
  return out;
}

TEST(SynthBillboard, PeopleGtAndMaskAgreeWithTheRenderAndEachOther) {
  TempDir tmp;
  test::write_test_sprites(tmp / "s", 5);
  const SynthOptions o = sprite_options(tmp / "s", 10, 45);
  write_sequence(o, tmp / "seq");
  const Scene scene = Scene::build(o);
  ASSERT_TRUE(scene.sprite_people());
  EXPECT_EQ(scene.crowd(), CrowdProfile::kPassing) << "auto with sprites";
  const auto gt = gt_by_frame(tmp / "seq" / "people_gt.txt");
  int full = 0;
  int occluded = 0;
  for (int f = 0; f < o.frames; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", f);
    const cv::Mat mask = cv::imread((tmp / "seq" / "people_mask" / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.type(), CV_16U) << name;
    const RenderedFrame r = render_frame(scene, f);
    ASSERT_EQ(cv::norm(mask, r.person_label, cv::NORM_INF), 0.0)
        << "the mask is the rendered label, frame " << f;
    const auto boxes = visible_person_boxes(scene, r, scene.trajectory()[f].world_from_cam, f);
    const auto lines = gt.count(f + 1) ? gt.at(f + 1) : std::map<int, std::vector<std::string>>();
    ASSERT_EQ(lines.size(), boxes.size()) << "frame " << f;
    for (const PersonBox& b : boxes) {
      SCOPED_TRACE("frame " + std::to_string(f) + " person " + std::to_string(b.id));
      ASSERT_TRUE(lines.count(b.id));
      const auto& fields = lines.at(b.id);
      ASSERT_EQ(fields.size(), 9u);
      EXPECT_EQ(fields[6], "1");
      EXPECT_EQ(fields[7], "1");
      const double x = std::stod(fields[2]), y = std::stod(fields[3]), w = std::stod(fields[4]),
                   h = std::stod(fields[5]);
      const double visibility = std::stod(fields[8]);
      EXPECT_NEAR(visibility, b.visibility, 5e-5);
      const cv::Mat mine = mask == b.id;
      EXPECT_EQ(cv::countNonZero(mine), b.visible_pixels);
      EXPECT_NEAR(visibility, b.visible_pixels / b.unbounded_pixels, 5e-5);
      EXPECT_GE(b.unbounded_pixels, b.pixels);
      ASSERT_GT(b.visible_pixels, 0);
      const cv::Rect e = cv::boundingRect(mine);  // the visible pixels lie inside the box
      EXPECT_GE(std::max(0.0, e.x - 0.5), x - 0.01);
      EXPECT_GE(std::max(0.0, e.y - 0.5), y - 0.01);
      EXPECT_LE(std::min(o.width - 1.0, e.x + e.width - 0.5), x + w + 0.01);
      EXPECT_LE(std::min(o.height - 1.0, e.y + e.height - 0.5), y + h + 0.01);
      if (b.visible_pixels ==
          b.pixels) {  // fully visible: the box is the mask's extent (pixel edges) within a pixel
        ++full;
        EXPECT_NEAR(x, std::max(0.0, e.x - 0.5), 1.0);
        EXPECT_NEAR(y, std::max(0.0, e.y - 0.5), 1.0);
        EXPECT_NEAR(x + w, std::min(o.width - 1.0, e.x + e.width - 0.5), 1.0);
        EXPECT_NEAR(y + h, std::min(o.height - 1.0, e.y + e.height - 0.5), 1.0);
      } else {
        EXPECT_GE(visibility, 0.0);
        EXPECT_LE(visibility, 1.0);
        occluded += b.visibility < 0.9;
      }
    }
    // Mirrored exactly while walking the other way across the view than the sprite's person (facing +1).
    for (const Billboard& b : scene.people_billboards(f)) {
      const PersonState& s = scene.people()[b.person_id - 1].states[f];
      const double across = std::cos(s.body_yaw) * b.axis.x() + std::sin(s.body_yaw) * b.axis.y();
      if (std::abs(across) > 0.35) {
        EXPECT_EQ(b.mirrored, across < 0.0) << "frame " << f << " person " << b.person_id;
      }
    }
  }
  EXPECT_GE(full, 10);
  EXPECT_GE(occluded, 3) << "ten people in a small room hide each other";
  const auto meta = nlohmann::json::parse(read_text(tmp / "seq" / "synth.json"));
  EXPECT_EQ(meta["people_model"], "sprites");
  EXPECT_EQ(meta["person_mask"], "people_mask");
  EXPECT_EQ(meta["crowd"], "passing");
  EXPECT_EQ(meta["persons"].size(), 10u);
}

TEST(SynthBillboard, TheRightCameraSeesThePeopleWhereTheLeftDepthPutsThem) {
  // Stereo: both cameras render the billboards that face the left one, so the people are one rigid scene.
  TempDir tmp;
  test::write_test_sprites(tmp / "s", 4);
  SynthOptions o = sprite_options(tmp / "s", 8, 60);
  o.stereo = true;
  const Scene scene = Scene::build(o);
  int checked = 0;
  for (int f = 0; f < o.frames; f += 6) {
    const RenderedFrame left = render_frame(scene, f, false);
    const RenderedFrame right = render_frame(scene, f, true);
    const double people = cv::countNonZero(left.person_label) / static_cast<double>(left.person_label.total());
    if (people < 0.1) continue;
    ++checked;
    // Every pixel, people included (no labels given): depth and colour agree in the right image.
    const auto c = test::check_consistency(left.colour, left.depth_m, {}, scene.trajectory()[f].world_from_cam,
                                           right.colour, right.depth_m, {}, scene.right_world_from_cam(f),
                                           scene.intrinsics(), 1);
    EXPECT_GT(c.depth_agrees, 0.9 * c.inside) << "frame " << f;
    EXPECT_LT(c.median_grey_diff, 6.0) << "frame " << f;
  }
  EXPECT_GE(checked, 3);
}

TEST(SynthBillboard, SameOptionsSameBytesRgbdAndStereo) {
  TempDir tmp;
  test::write_test_sprites(tmp / "s", 3);
  for (bool stereo : {false, true}) {
    SynthOptions o = sprite_options(tmp / "s", 4, 4);
    o.stereo = stereo;
    const std::string tag = stereo ? "stereo" : "rgbd";
    write_sequence(o, tmp / (tag + "_a"));
    write_sequence(o, tmp / (tag + "_b"));
    int compared = 0;
    for (const auto& entry : fs::recursive_directory_iterator(tmp / (tag + "_a"))) {
      if (!entry.is_regular_file()) continue;
      const fs::path rel = fs::relative(entry.path(), tmp / (tag + "_a"));
      EXPECT_EQ(read_text(entry.path()), read_text(tmp / (tag + "_b") / rel)) << rel;
      ++compared;
    }
    EXPECT_EQ(compared, 4 * 3 + (stereo ? 7 : 6)) << tag;  // 2 images + mask per frame; text files
  }
}

TEST(SynthBillboard, WithoutSpritesTheCliSaysSoOnceAndDrawsBoxes) {
  TempDir tmp;
  const std::vector<std::string> common = {"synth",   "--frames", "3",        "--people", "2",
                                           "--width", "160",      "--height", "120"};
  auto args = common;
  args.insert(args.end(), {"--out", (tmp / "boxes").string(), "--sprites", "none"});
  const auto r = crowdslam::test::run_cli(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int notices = 0;
  std::istringstream err(r.err);
  for (std::string line; std::getline(err, line);)
    notices += line.find("textured boxes") != std::string::npos;
  EXPECT_EQ(notices, 1) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "boxes" / "people_mask"));
  const auto meta = nlohmann::json::parse(read_text(tmp / "boxes" / "synth.json"));
  EXPECT_EQ(meta["people_model"], "boxes");
  EXPECT_EQ(meta["crowd"], "walk");
  for (const std::string& line : read_lines((tmp / "boxes" / "people_gt.txt").string())) {
    EXPECT_EQ(split_fields(line).size(), 10u);
  }
  // The same sequence through the library without sprites: the box people of before.
  SynthOptions o;
  o.frames = 3;
  o.people = 2;
  o.width = 160;
  o.height = 120;
  const Scene scene = Scene::build(o);
  EXPECT_FALSE(scene.sprite_people());
  EXPECT_EQ(scene.moving_boxes(0).size(), 2u);
  EXPECT_EQ(read_text(tmp / "boxes" / "rgb" / "000002.png"), [&] {
    std::vector<unsigned char> png;
    cv::imencode(".png", render_frame(scene, 2).colour, png,
                 {cv::IMWRITE_PNG_COMPRESSION, 1, cv::IMWRITE_PNG_STRATEGY, cv::IMWRITE_PNG_STRATEGY_RLE});
    return std::string(png.begin(), png.end());
  }());
  // With sprites: no notice, billboards, the mask and 9 columns.
  test::write_test_sprites(tmp / "s", 2);
  args = common;
  args.insert(args.end(), {"--out", (tmp / "sprites").string(), "--sprites", (tmp / "s").string()});
  const auto with = crowdslam::test::run_cli(args);
  ASSERT_EQ(with.exit_code, 0) << with.err;
  EXPECT_EQ(with.err.find("textured boxes"), std::string::npos) << with.err;
  EXPECT_TRUE(fs::exists(tmp / "sprites" / "people_mask" / "000002.png"));
  args.back() = (tmp / "missing").string();
  const auto missing = crowdslam::test::run_cli(args);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("sprites.json"), std::string::npos) << missing.err;
}

}  // namespace
}  // namespace crowdslam::synth
