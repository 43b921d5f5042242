// The people filter scored against person masks (run/filter_mask_score.h, `crowdslam run --score-filter`):
// exact counts on a hand-made mask, and on a synthetic crowd the generator's exact boxes remove the
// people's keypoints and keep the background, while a run without the filter removes nothing.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "crowdslam/io/opencv_extras.h"
#include "crowdslam/run/filter_mask_score.h"
#include "crowdslam/synth/sprites.h"
#include "crowdslam/system/system.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace fs = std::filesystem;
using crowdslam::run::FilterMaskScore;
using crowdslam::run::kEdgeRadiusPx;
using crowdslam::test::run_cli;

namespace {
nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}
}  // namespace

TEST(FilterMaskScore, CountsKeptAndRemovedKeypointsOnPeopleEdgesAndBackground) {
  crowdslam::test::TempDir tmp;
  const fs::path masks = tmp / "people_mask";
  fs::create_directories(masks);
  // Frame 0: person 7 covers x 100-199, y 50-249 (16-bit ids, as synth writes them). Frame 1 has no mask.
  cv::Mat mask(480, 640, CV_16UC1, cv::Scalar(0));
  mask(cv::Rect(100, 50, 100, 200)).setTo(7);
  ASSERT_TRUE(crowdslam::io::opencv_extras().imwrite((masks / "000000.png").string(), mask, {}));

  FilterMaskScore score(masks);
  crowdslam::system::FrameReport report;
  report.index = 0;
  auto key = [](float x, float y) { return cv::KeyPoint(x, y, 31.0f); };
  report.kept_keypoints = {key(150, 100),                      // on the person
                           key(200 + kEdgeRadiusPx - 1, 100),  // edge: within the radius, right side
                           key(200 + kEdgeRadiusPx + 2, 100),  // clear background
                           key(400, 400),
                           key(20, 20),                      // background
                           key(700, 10)};                    // outside the image
  report.removed_keypoints = {key(120, 60), key(199, 249),   // on the person (its corners)
                              key(100, 50 - kEdgeRadiusPx),  // edge above
                              key(600, 300)};                // background
  score.on_frame(report, std::nullopt, {});
  crowdslam::system::FrameReport second;
  second.index = 1;
  second.kept_keypoints = {key(150, 100)};
  score.on_frame(second, std::nullopt, {});

  const auto& c = score.counts();
  EXPECT_EQ(c.frames_scored, 1u);
  EXPECT_EQ(c.frames_without_mask, 1u);
  EXPECT_EQ(c.kept_on_people, 1u);
  EXPECT_EQ(c.kept_on_edges, 1u);
  EXPECT_EQ(c.kept_on_background, 3u);
  EXPECT_EQ(c.outside_mask, 1u);
  EXPECT_EQ(c.removed_on_people, 2u);
  EXPECT_EQ(c.removed_on_edges, 1u);
  EXPECT_EQ(c.removed_on_background, 1u);
  const auto j = score.to_json();
  EXPECT_DOUBLE_EQ(j.at("people_removed").get<double>(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(j.at("background_kept").get<double>(), 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(j.at("kept_on_people_share").get<double>(), 2.0 / 5.0);
}

TEST(FilterMaskScore, ADirectoryWithoutMasksIsAnInputError) {
  crowdslam::test::TempDir tmp;
  EXPECT_THROW(FilterMaskScore(tmp / "people_mask"), crowdslam::InputError);
}

TEST(FilterMaskScore, ExactBoxesRemoveThePeopleAndKeepTheBackgroundOfASyntheticCrowd) {
  if (!fs::exists(crowdslam::synth::default_sprite_dir() / "sprites.json")) {
    GTEST_SKIP() << "person sprites missing (scripts/build_people_sprites.sh)";
  }
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "crowd";
  const auto synth = run_cli({"-q", "synth", "--out", seq.string(), "--frames", "40", "--seed", "5",
                              "--people", "8", "--crowd", "passing"});
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  const std::string boxes = (seq / "people_gt.txt").string();
  const auto filtered = run_cli({"-q", "run", "--dataset", seq.string(), "--out", (tmp / "gt").string(),
                                 "--sequential", "--detections", boxes, "--score-filter"});
  ASSERT_EQ(filtered.exit_code, 0) << filtered.err;
  const auto doc = read_json(tmp / "gt" / "run.json");
  const auto& m = doc.at("people_masks");
  EXPECT_EQ(m.at("frames_scored").get<size_t>(), 40u);
  EXPECT_EQ(m.at("frames_without_mask").get<size_t>(), 0u);
  // Every keypoint extracted is counted once: kept or removed, somewhere.
  size_t extracted = 0;
  for (const auto& f : doc.at("frames")) extracted += f.at("keypoints_before_filter").get<size_t>();
  size_t counted = m.at("outside_mask").get<size_t>();
  for (const char* k : {"kept_on_people", "kept_on_edges", "kept_on_background", "removed_on_people",
                        "removed_on_edges", "removed_on_background"}) {
    counted += m.at(k).get<size_t>();
  }
  EXPECT_EQ(counted, extracted);
  EXPECT_GT(m.at("removed_on_people").get<size_t>(), 0u);
  EXPECT_GT(m.at("people_removed").get<double>(), 0.8);
  EXPECT_GT(m.at("background_kept").get<double>(), 0.9);

  // Without the filter nothing is removed, and the people's keypoints are all kept.
  const auto unfiltered = run_cli({"-q", "run", "--dataset", seq.string(), "--out", (tmp / "off").string(),
                                   "--sequential", "--no-people-filter", "--score-filter"});
  ASSERT_EQ(unfiltered.exit_code, 0) << unfiltered.err;
  const auto o = read_json(tmp / "off" / "run.json").at("people_masks");
  EXPECT_EQ(o.at("removed_on_people").get<size_t>() + o.at("removed_on_edges").get<size_t>() +
                o.at("removed_on_background").get<size_t>(),
            0u);
  EXPECT_GT(o.at("kept_on_people").get<size_t>(), 0u);
}

TEST(FilterMaskScore, RunWithoutPersonMasksFailsBeforeAnyOutput) {
  crowdslam::test::TempDir tmp;
  const auto seq = tmp / "room";
  const auto synth = run_cli({"-q", "synth", "--out", seq.string(), "--frames", "5", "--people", "0"});
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  fs::remove_all(seq / "people_mask");  // a dataset without person masks (a recorded one)
  const auto out = tmp / "out";
  const auto r = run_cli(
      {"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--sequential", "--score-filter"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("people_mask"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}
