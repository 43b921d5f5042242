// MOT files with boxes of negative or absurd size (issue 10): skipped, counted and warned once with the
// first FILE:LINE, whether read by the MOT-file detector or by the detection evaluation.
#include <gtest/gtest.h>

#include "../io/log_capture.h"
#include "crowdslam/people/mot_file_detector.h"
#include "crowdslam/people/mot_format.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {

TEST(MotInput, NegativeAndHugeBoxesAreSkippedCountedAndWarnedOnce) {
  test::TempDir dir;
  const std::string path = (dir / "det.txt").string();
  test::write_text(path,
                   "1,-1,10,20,30,40,0.9,-1,-1,-1\n"
                   "1,-1,10,20,-30,40,0.9,-1,-1,-1\n"   // negative width
                   "2,-1,10,20,30,1e9,0.9,-1,-1,-1\n"   // a billion pixels high
                   "2,-1,1e30,20,30,40,0.9,-1,-1,-1\n"  // far outside any image
                   "3,-1,10,20,30,0,0.9,-1,-1,-1\n");   // zero height
  test::LogCapture log;
  const MotFile file = read_mot_file(path);
  ASSERT_EQ(file.rows.size(), 1u);
  EXPECT_EQ(file.dropped_empty, 2u);
  EXPECT_EQ(file.dropped_out_of_range, 2u);
  EXPECT_EQ(file.first_dropped_line, 2);
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0],
            path +
                ":2: 4 boxes skipped: 2 with zero or negative width/height, 2 with a coordinate or "
                "size beyond 1e6 pixels");
}

TEST(MotInput, TheMotFileDetectorWarnsOnceToo) {
  test::TempDir dir;
  const std::string path = (dir / "det.txt").string();
  test::write_text(path, "1,-1,10,20,30,40,1\n1,-1,10,20,30,-4,1\n2,-1,10,20,3e8,40,1\n");
  test::LogCapture log;
  const MotFileDetector detector(path, {});
  EXPECT_EQ(detector.box_count(), 1u);
  EXPECT_EQ(detector.dropped_empty(), 1u);
  ASSERT_EQ(log.warnings().size(), 1u);
  EXPECT_NE(log.warnings()[0].find(path + ":2: 2 boxes skipped"), std::string::npos) << log.warnings()[0];
}

TEST(MotInput, CleanFileGivesNoWarning) {
  test::TempDir dir;
  test::write_text(dir / "det.txt", "1,-1,-5,20,30,40,1\n2,-1,600,400,80,120,1\n");  // partly outside: fine
  test::LogCapture log;
  EXPECT_EQ(read_mot_file((dir / "det.txt").string()).rows.size(), 2u);
  EXPECT_TRUE(log.warnings().empty());
}

TEST(MotInput, NonIntegerOrHugeIdIsAnErrorNamingTheLine) {
  test::TempDir dir;
  test::write_text(dir / "det.txt", "1,-1,10,20,30,40,1\n1,1e20,10,20,30,40,1\n");
  const std::string message = test::error_of([&] { (void)read_mot_file((dir / "det.txt").string()); });
  EXPECT_NE(message.find("det.txt:2: id must be an integer"), std::string::npos) << message;
}

// Issue 37, finding 7: a frame with more boxes than kMaxBoxesPerFrame keeps its most confident ones (in
// file order, the first of equal scores first); the rest are counted and warned about once.
TEST(MotInput, AFrameBeyondTheBoxCapKeepsItsMostConfidentBoxes) {
  test::TempDir dir;
  const std::string path = (dir / "det.txt").string();
  std::string text;
  const std::size_t weak = 3 * kMaxBoxesPerFrame;
  for (std::size_t i = 0; i < weak; ++i) text += "1,-1,100,100,20,40,0.5\n";
  for (std::size_t i = 0; i < kMaxBoxesPerFrame - 10; ++i) text += "1,-1," + std::to_string(i % 50) + ",1,20,40,0.9\n";
  for (int i = 0; i < 5; ++i) text += "2,-1,1,1,20,40,0.1\n";  // under the cap: all kept, whatever their score
  test::write_text(path, text);
  test::LogCapture log;
  const MotFile file = read_mot_file(path);
  EXPECT_EQ(file.capped_frames, 1u);
  EXPECT_EQ(file.dropped_over_cap, weak - 10);
  ASSERT_EQ(file.rows.size(), kMaxBoxesPerFrame + 5);
  // The 10 weak boxes kept are the first 10 of the file; then every strong one; then frame 2.
  for (std::size_t i = 0; i < 10; ++i) EXPECT_EQ(file.rows[i].line, static_cast<int>(i + 1));
  for (std::size_t i = 10; i < kMaxBoxesPerFrame; ++i) EXPECT_DOUBLE_EQ(file.rows[i].score, 0.9);
  EXPECT_EQ(file.rows.back().frame, 2);
  const auto warnings = log.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("1 frame with more than 2000 person boxes (first: frame 1); kept the 2000 most "
                             "confident of each, skipped 5990 boxes"),
            std::string::npos)
      << warnings[0];
}

}  // namespace
}  // namespace crowdslam::people
