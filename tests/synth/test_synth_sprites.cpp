// Person sprites (synth/sprites.h): grabCut cut-outs from MOT sequences, loading and finding them.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "crowdslam/synth/rng.h"
#include "crowdslam/synth/sprites.h"
#include "crowdslam/util/error.h"
#include "synth_test_util.h"
#include "test_support.h"

namespace crowdslam::synth {
namespace {
namespace fs = std::filesystem;
using crowdslam::test::read_text;
using crowdslam::test::TempDir;

// A noisy, colourful background with a person-like shape (synth_test_util's sprite shape scaled 1.5x,
// in a colour of its own) standing in it; the shape's mask is returned in `truth`.
cv::Mat scene_with_person(const cv::Point& top_left, cv::Mat& truth) {
  cv::Mat image(400, 400, CV_8UC3);
  Rng rng(3);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const double band = ((x / 25 + y / 40) % 3) * 50.0;
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(60 + band + rng.uniform(-20, 20)),
                                            cv::saturate_cast<uchar>(140 + rng.uniform(-20, 20)),
                                            cv::saturate_cast<uchar>(90 + band / 2 + rng.uniform(-20, 20)));
    }
  }
  truth = cv::Mat::zeros(image.size(), CV_8U);
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 90; ++x) {
      if (!test::test_sprite_opaque(x * 2 / 3, y * 2 / 3)) continue;
      image.at<cv::Vec3b>(top_left.y + y, top_left.x + x) = cv::Vec3b(30, 40, 200 + (x + y) % 30);
      truth.at<uchar>(top_left.y + y, top_left.x + x) = 255;
    }
  }
  return image;
}

TEST(SynthSprites, GrabCutFindsThePersonInItsBoxAndRejectsABoxAroundLittle) {
  cv::Mat truth;
  const cv::Mat image = scene_with_person({150, 100}, truth);
  const cv::Rect box(148, 98, 94, 244);  // the shape's rectangle and a 2 px margin
  SpriteExtractOptions options;
  double fill = 0.0;
  const auto sprite = cut_out_person(image, box, options, &fill);
  ASSERT_TRUE(sprite.has_value());
  ASSERT_EQ(sprite->type(), CV_8UC4);
  int opaque = 0;
  for (int y = 0; y < sprite->rows; ++y) {
    for (int x = 0; x < sprite->cols; ++x) {
      const uchar a = sprite->at<cv::Vec4b>(y, x)[3];
      ASSERT_TRUE(a == 0 || a == 255);
      if (a == 0) {
        EXPECT_EQ(sprite->at<cv::Vec4b>(y, x), cv::Vec4b(0, 0, 0, 0)) << "transparent texels carry no colour";
        continue;
      }
      ++opaque;
    }
  }
  // The sprite is about the shape's bounding rectangle (90 x 240; grabCut may lose a thin arm's edge).
  EXPECT_NEAR(sprite->cols, 90, 8);
  EXPECT_NEAR(sprite->rows, 240, 6);
  const int shape_pixels = cv::countNonZero(truth);
  EXPECT_NEAR(opaque, shape_pixels, 0.08 * shape_pixels);
  EXPECT_NEAR(fill, static_cast<double>(shape_pixels) / box.area(), 0.05);
  // Top and bottom rows reach the head and the feet.
  cv::Mat alpha;
  cv::extractChannel(*sprite, alpha, 3);
  EXPECT_GT(cv::countNonZero(alpha.row(0)), 0);
  EXPECT_GT(cv::countNonZero(alpha.row(alpha.rows - 1)), 0);
  // A box three times as wide as the person: too little of it is the person.
  EXPECT_FALSE(cut_out_person(image, cv::Rect(60, 98, 280, 244), options).has_value());
  // Deterministic.
  const auto again = cut_out_person(image, box, options);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(cv::norm(*sprite, *again, cv::NORM_INF), 0.0);
}

TEST(SynthSprites, CutsPlausiblePeopleOutOfMotSequencesDeterministically) {
  CROWDSLAM_REQUIRE_SHARED("mot");
  const fs::path sequence = crowdslam::test::shared_data("mot") / "TUD-Stadtmitte";
  ASSERT_EQ(find_mot_sequences(sequence), std::vector<fs::path>{sequence});
  EXPECT_GE(find_mot_sequences(crowdslam::test::shared_data("mot")).size(), 2u);
  TempDir tmp;
  SpriteExtractOptions options;
  options.per_id = 1;
  options.max_sprites = 5;
  const SpriteSet set = extract_sprites({sequence}, tmp / "a", options, false);
  ASSERT_GE(set.sprites.size(), 4u) << "TUD-Stadtmitte has 10 people, most of them tall and apart at times";
  ASSERT_EQ(set.sequences.size(), 1u);
  EXPECT_EQ(set.sequences[0].sprites, static_cast<int>(set.sprites.size()));
  EXPECT_GT(set.sequences[0].candidates, 20);
  std::set<int> ids;
  for (const SpriteRecord& r : set.sprites) {
    SCOPED_TRACE(r.file);
    ids.insert(r.id);
    const cv::Mat png = cv::imread((tmp / "a" / r.file).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(png.type(), CV_8UC4);
    EXPECT_EQ(png.cols, r.width);
    EXPECT_EQ(png.rows, r.height);
    EXPECT_GE(png.rows, 0.84 * options.min_height_px) << "reaches from near the box's top to near its bottom";
    cv::Mat alpha;
    cv::extractChannel(png, alpha, 3);
    EXPECT_EQ(cv::countNonZero(alpha == 0) + cv::countNonZero(alpha == 255), static_cast<int>(alpha.total()));
    EXPECT_GT(cv::countNonZero(alpha.row(0)), 0);
    EXPECT_GT(cv::countNonZero(alpha.row(alpha.rows - 1)), 0);
    const double tight_fill = cv::countNonZero(alpha) / static_cast<double>(alpha.total());
    EXPECT_GT(tight_fill, 0.35);
    EXPECT_LT(tight_fill, 0.95);
    EXPECT_GE(r.fill, options.min_fill);
    EXPECT_LE(r.fill, options.max_fill);
    EXPECT_GT(png.rows, 1.6 * png.cols) << "a standing person is taller than wide";
  }
  EXPECT_EQ(ids.size(), set.sprites.size()) << "one sprite per person";
  const auto list = nlohmann::json::parse(read_text(tmp / "a" / "sprites.json"));
  EXPECT_EQ(list["count"], set.sprites.size());
  EXPECT_EQ(list["sprites"][0]["sequence"], "TUD-Stadtmitte");
  // The same again: the same bytes.
  extract_sprites({sequence}, tmp / "b", options, false);
  int compared = 0;
  for (const auto& entry : fs::directory_iterator(tmp / "a")) {
    EXPECT_EQ(read_text(entry.path()), read_text(tmp / "b" / entry.path().filename())) << entry.path();
    ++compared;
  }
  EXPECT_EQ(compared, static_cast<int>(set.sprites.size()) + 1);
  // Loadable: every listed sprite, its alpha as written.
  const std::vector<Sprite> loaded = load_sprites(tmp / "a");
  ASSERT_EQ(loaded.size(), set.sprites.size());
  EXPECT_EQ(loaded[0].alpha.cols, set.sprites[0].width);
  // A second run into a full directory needs force.
  EXPECT_NE(crowdslam::test::error_of([&] {
              extract_sprites({sequence}, tmp / "a", options, false);
            }).find("--force"),
            std::string::npos);
}

TEST(SynthSprites, LoadingNamesTheBrokenFile) {
  TempDir tmp;
  const fs::path dir = tmp / "sprites";
  EXPECT_NE(crowdslam::test::error_of([&] { load_sprites(dir); }).find("sprites.json"), std::string::npos);
  test::write_test_sprites(dir, 3);
  const std::vector<Sprite> sprites = load_sprites(dir);
  ASSERT_EQ(sprites.size(), 3u);
  EXPECT_NEAR(sprites[1].aspect(), 60.0 / 160.0, 1e-12);
  EXPECT_TRUE(sprites[0].opaque(30, 50));    // torso
  EXPECT_FALSE(sprites[0].opaque(30, 150));  // between the legs
  EXPECT_FALSE(sprites[0].opaque(1, 5));     // beside the head
  // Transparent texels get the colour of their opaque neighbours (no black fringe when filtered).
  const cv::Vec3f beside_torso = sprites[0].colour.sample(8.0, 60.0, 0.0);
  const cv::Vec3f torso = sprites[0].colour.sample(12.0, 60.0, 0.0);
  EXPECT_LT(cv::norm(beside_torso - torso), 40.0);
  fs::remove(dir / "test_1.png");
  EXPECT_NE(crowdslam::test::error_of([&] { load_sprites(dir); }).find("test_1.png"), std::string::npos);
  cv::imwrite((dir / "test_1.png").string(), cv::Mat(160, 60, CV_8UC3, cv::Scalar::all(9)));
  EXPECT_NE(crowdslam::test::error_of([&] { load_sprites(dir); }).find("4-channel"), std::string::npos);
  crowdslam::test::write_text(dir / "sprites.json", "{\"sprites\": []}");
  EXPECT_NE(crowdslam::test::error_of([&] { load_sprites(dir); }).find("lists no sprites"),
            std::string::npos);
}

TEST(SynthSprites, TheChoiceOfSpritesSaysInOneLineWhenPeopleAreBoxes) {
  const SpriteChoice none = resolve_sprite_dir("none");
  EXPECT_TRUE(none.dir.empty());
  EXPECT_NE(none.notice.find("boxes"), std::string::npos);
  EXPECT_EQ(none.notice.find('\n'), std::string::npos);
  TempDir tmp;
  EXPECT_NE(
      crowdslam::test::error_of([&] { resolve_sprite_dir((tmp / "nothing").string()); }).find("sprites.json"),
      std::string::npos);
  test::write_test_sprites(tmp / "s", 1);
  EXPECT_EQ(resolve_sprite_dir((tmp / "s").string()).dir, (tmp / "s").string());
  EXPECT_TRUE(resolve_sprite_dir((tmp / "s").string()).notice.empty());
  // The default: <repo>/people_sprites when built, else boxes with one line on how to build them.
  const SpriteChoice fallback = resolve_sprite_dir("");
  if (has_sprites(default_sprite_dir())) {
    EXPECT_EQ(fallback.dir, default_sprite_dir().string());
  } else {
    EXPECT_TRUE(fallback.dir.empty());
    EXPECT_NE(fallback.notice.find("build_people_sprites.sh"), std::string::npos);
    EXPECT_EQ(fallback.notice.find('\n'), std::string::npos);
  }
}

}  // namespace
}  // namespace crowdslam::synth
