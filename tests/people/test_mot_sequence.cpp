// MOT sequence folders (seqinfo.ini + img1/) and the default model lookup.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "crowdslam/people/model_paths.h"
#include "crowdslam/people/mot_sequence.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {
namespace fs = std::filesystem;

void write_image(const fs::path& path, int value) {
  fs::create_directories(path.parent_path());
  cv::imwrite(path.string(), cv::Mat(6, 8, CV_8UC3, cv::Scalar::all(value)));
}

TEST(MotSequence, ReadsSeqinfoLengthAndRate) {
  test::TempDir dir;
  test::write_text(dir / "seqinfo.ini",
                   "[Sequence]\nname=x\nimDir=img1\nframeRate=25\nseqLength=3\nimExt=.png\n");
  for (int i = 1; i <= 4; ++i) write_image(dir / "img1" / ("00000" + std::to_string(i) + ".png"), 10 * i);
  ASSERT_TRUE(looks_like_mot_sequence(dir.path().string()));
  auto seq = open_detection_source(dir.path().string());
  EXPECT_EQ(seq->layout(), "mot");
  const auto* dataset = dynamic_cast<io::Dataset*>(seq.get());
  ASSERT_NE(dataset, nullptr);
  EXPECT_EQ(dataset->size(), 3u);  // seqLength, not the 4 files
  EXPECT_DOUBLE_EQ(dataset->frame_info(2).timestamp_s, 2.0 / 25.0);
  auto frame = seq->next();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->images.colour.at<cv::Vec3b>(0, 0)[0], 10);
}

TEST(MotSequence, WithoutSeqinfoListsImg1) {
  test::TempDir dir;
  for (int i = 1; i <= 2; ++i) write_image(dir / "img1" / ("00000" + std::to_string(i) + ".jpg"), 10 * i);
  auto seq = open_mot_sequence(dir.path().string());
  EXPECT_EQ(seq->size(), 2u);
}

TEST(MotSequence, MissingImageAndBadIniNameTheFile) {
  test::TempDir dir;
  test::write_text(dir / "seqinfo.ini", "[Sequence]\nseqLength=2\n");
  write_image(dir / "img1" / "000001.jpg", 1);
  try {
    open_mot_sequence(dir.path().string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("000002.jpg"), std::string::npos) << e.what();
  }
  test::write_text(dir / "seqinfo.ini", "[Sequence]\nframeRate=fast\n");
  try {
    open_mot_sequence(dir.path().string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("seqinfo.ini"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("frameRate"), std::string::npos) << e.what();
  }
}

TEST(MotSequence, SharedTudCampusHas71Frames) {
  CROWDSLAM_REQUIRE_SHARED("mot");
  auto seq = open_mot_sequence((test::shared_data("mot") / "TUD-Campus").string());
  EXPECT_EQ(seq->size(), 71u);
  EXPECT_DOUBLE_EQ(seq->summary().fps, 25.0);
}

TEST(ModelPaths, EnvironmentOverrideAndNames) {
  test::TempDir dir;
  fs::create_directories(dir / "yolo-fastest-1.1");
  ::setenv("CROWDSLAM_MODELS", dir.path().c_str(), 1);
  EXPECT_EQ(default_model_dir(), dir.path().string());
  const ModelFiles body = resolve_model("body");
  EXPECT_EQ(body.config, (dir / "yolo-fastest-1.1" / "yolo-fastest-1.1_body.cfg").string());
  EXPECT_EQ(body.weights, (dir / "yolo-fastest-1.1" / "yolo-fastest-1.1_body.weights").string());
  EXPECT_EQ(resolve_model("coco").config, (dir / "yolo-fastest-1.1" / "yolo-fastest-1.1.cfg").string());
  ::unsetenv("CROWDSLAM_MODELS");
  EXPECT_EQ(resolve_model("/x/net.cfg").weights, "/x/net.weights");
  EXPECT_TRUE(resolve_model("/x/net.onnx").weights.empty());
  try {
    resolve_model("yolo9000");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("yolo9000"), std::string::npos);
  }
}

}  // namespace
}  // namespace crowdslam::people
