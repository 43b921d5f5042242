// MOT files as a detector: frame lookup, thresholds, bad input (clipping, empty boxes, NaN, short files).
#include <gtest/gtest.h>

#include "crowdslam/people/mot_file_detector.h"
#include "crowdslam/people/mot_format.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {

const cv::Mat kImage(100, 200, CV_8UC3, cv::Scalar::all(0));  // 200 x 100

std::string error_of(const std::string& path) {
  try {
    MotFileDetector d(path, {});
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(MotFileDetector, FramesAreOneBasedAndThresholded) {
  test::TempDir dir;
  test::write_text(dir / "det.txt",
                   "1,-1,10,20,30,40,0.9,-1,-1,-1\n"
                   "1,-1,50,20,30,40,0.1,-1,-1,-1\n"  // below 0.2: dropped
                   "3,-1,0,0,5,6,0.5,-1,-1,-1\n");
  MotFileDetector d((dir / "det.txt").string(), {});
  EXPECT_EQ(d.box_count(), 2u);
  EXPECT_EQ(d.last_frame(), 3);
  const Detections f0 = d.detect(kImage, 0);
  ASSERT_EQ(f0.boxes.size(), 1u);
  EXPECT_FLOAT_EQ(f0.boxes[0].box.x, 10);
  EXPECT_FLOAT_EQ(f0.boxes[0].box.height, 40);
  EXPECT_FLOAT_EQ(f0.boxes[0].confidence, 0.9f);
  EXPECT_EQ(f0.raw.size(), 1u);
  EXPECT_TRUE(d.detect(kImage, 1).boxes.empty());  // frame 2 absent
  EXPECT_EQ(d.detect(kImage, 2).boxes.size(), 1u);
  // The file ends at frame 3; later frames of a longer sequence have no boxes.
  EXPECT_TRUE(d.detect(kImage, 500).boxes.empty());
}

TEST(MotFileDetector, ClipsToTheImageAndDropsEmptyBoxes) {
  test::TempDir dir;
  test::write_text(dir / "det.txt",
                   "1,-1,-10,-10,30,40,1\n"  // clipped to 0,0,20,30
                   "1,-1,190,90,30,40,1\n"   // clipped to 190,90,10,10
                   "1,-1,300,10,30,40,1\n"   // entirely outside: dropped
                   "1,-1,10,10,0,40,1\n"     // zero width: dropped when read
                   "1,-1,10,10,20,-4,1\n");  // negative height: dropped when read
  MotFileDetector d((dir / "det.txt").string(), {});
  EXPECT_EQ(d.dropped_empty(), 2u);
  const Detections f = d.detect(kImage, 0);
  ASSERT_EQ(f.boxes.size(), 2u);
  EXPECT_EQ(f.boxes[0].box, cv::Rect2f(0, 0, 20, 30));
  EXPECT_EQ(f.boxes[1].box, cv::Rect2f(190, 90, 10, 10));
}

TEST(MotFileDetector, NaNAndGarbageAreErrorsNamingFileAndLine) {
  test::TempDir dir;
  test::write_text(dir / "nan.txt", "1,-1,10,20,30,40,0.9\n2,-1,10,20,30,40,nan\n");
  EXPECT_NE(error_of((dir / "nan.txt").string()).find("nan.txt:2"), std::string::npos);
  test::write_text(dir / "nanbox.txt", "1,-1,10,NaN,30,40,0.9\n");
  EXPECT_NE(error_of((dir / "nanbox.txt").string()).find("nanbox.txt:1"), std::string::npos);
  test::write_text(dir / "short.txt", "1,-1,10,20,30\n");
  EXPECT_NE(error_of((dir / "short.txt").string()).find("short.txt:1"), std::string::npos);
  test::write_text(dir / "frame.txt", "\n# comment\n0,-1,10,20,30,40,1\n");
  EXPECT_NE(error_of((dir / "frame.txt").string()).find("frame.txt:3"), std::string::npos);
  test::write_text(dir / "word.txt", "1,-1,10,20,abc,40,1\n");
  EXPECT_NE(error_of((dir / "word.txt").string()).find("word.txt:1"), std::string::npos);
  EXPECT_NE(error_of((dir / "missing.txt").string()).find("missing.txt"), std::string::npos);
}

TEST(MotFormat, WriteThenReadRoundTrip) {
  test::TempDir dir;
  const std::string path = (dir / "out.txt").string();
  write_mot_detections(path, {{0, {{{1.5f, 2, 3, 4}, 0.75f}}}, {4, {{{10, 20, 30, 40}, 0.5f}}}});
  EXPECT_EQ(test::read_text(path), "1,-1,1.5,2,3,4,0.75,-1,-1,-1\n5,-1,10,20,30,40,0.5,-1,-1,-1\n");
  const MotFile f = read_mot_file(path);
  ASSERT_EQ(f.rows.size(), 2u);
  EXPECT_EQ(f.rows[1].frame, 5);
  EXPECT_EQ(f.columns, 10u);
}

}  // namespace
}  // namespace crowdslam::people
