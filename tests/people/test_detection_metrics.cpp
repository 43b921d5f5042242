// Detection metrics on hand-built cases with closed-form answers.
#include <gtest/gtest.h>

#include <cmath>

#include "crowdslam/people/detection_metrics.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

namespace crowdslam::people {
namespace {

DetectionCounts eval_files(const std::string& gt, const std::string& det, DetectionEvalOptions options = {}) {
  test::TempDir dir;
  test::write_text(dir / "gt.txt", gt);
  test::write_text(dir / "det.txt", det);
  return evaluate_detections(read_mot_file((dir / "gt.txt").string(), true),
                             read_mot_file((dir / "det.txt").string()), options);
}

TEST(DetectionMetrics, OneMatchOneMissOneFalse) {
  // gt A = [0,100]x[0,100]; det with IoU 0.8: [0,100]x[0,80] (inter 8000 / union 10000).
  // gt B far away is missed; a det elsewhere is false.
  const DetectionCounts c = eval_files("1,1,0,0,100,100,1,-1,-1,-1\n1,2,300,300,50,100,1,-1,-1,-1\n",
                                       "1,-1,0,0,100,80,0.9,-1,-1,-1\n1,-1,500,0,50,100,0.8,-1,-1,-1\n");
  EXPECT_EQ(c.true_positives, 1u);
  EXPECT_EQ(c.false_negatives, 1u);
  EXPECT_EQ(c.false_positives, 1u);
  EXPECT_EQ(c.ground_truth, 2u);
  EXPECT_DOUBLE_EQ(c.precision(), 0.5);
  EXPECT_DOUBLE_EQ(c.recall(), 0.5);
  EXPECT_DOUBLE_EQ(c.moda(), 0.0);
  EXPECT_NEAR(c.modp(), 0.8, 1e-6);
}

TEST(DetectionMetrics, HungarianBeatsGreedyAndModpIsMeanIouOfPairs) {
  // 1-D overlaps (same y and height): g1 = [0,10], g2 = [3,13], d1 = [1,11], d2 = [-3,7] (clipped in no
  // way: the metric does not clip). IoU(g1,d1) = 9/11, IoU(g2,d1) = 8/12, IoU(g1,d2) = 7/13,
  // IoU(g2,d2) = 4/16. Greedy takes g1-d1 and leaves g2 unmatched; the optimum is g1-d2, g2-d1.
  const DetectionCounts c =
      eval_files("1,1,0,0,10,10,1\n1,2,3,0,10,10,1\n", "1,-1,1,0,10,10,1\n1,-1,-3,0,10,10,1\n");
  EXPECT_EQ(c.true_positives, 2u);
  EXPECT_EQ(c.false_positives, 0u);
  EXPECT_EQ(c.false_negatives, 0u);
  EXPECT_DOUBLE_EQ(c.moda(), 1.0);
  EXPECT_NEAR(c.modp(), (7.0 / 13.0 + 8.0 / 12.0) / 2.0, 1e-6);
}

TEST(DetectionMetrics, FramesAreMatchedSeparately) {
  // The same box in frame 1 (gt) and frame 2 (det) is a miss and a false positive, not a match.
  const DetectionCounts c = eval_files("1,1,0,0,10,10,1\n", "2,-1,0,0,10,10,1\n");
  EXPECT_EQ(c.true_positives, 0u);
  EXPECT_EQ(c.false_negatives, 1u);
  EXPECT_EQ(c.false_positives, 1u);
  EXPECT_EQ(c.frames, 2u);
  EXPECT_DOUBLE_EQ(c.moda(), -1.0);
  EXPECT_TRUE(std::isnan(c.modp()));
  EXPECT_DOUBLE_EQ(c.precision(), 0.0);
}

TEST(DetectionMetrics, IouThresholdDecides) {
  // IoU 0.8 matches at 0.5 but not at 0.9.
  DetectionEvalOptions strict;
  strict.iou_threshold = 0.9;
  const DetectionCounts c = eval_files("1,1,0,0,100,100,1\n", "1,-1,0,0,100,80,1\n", strict);
  EXPECT_EQ(c.true_positives, 0u);
  EXPECT_EQ(c.false_positives, 1u);
  EXPECT_EQ(c.false_negatives, 1u);
}

TEST(DetectionMetrics, FlagZeroRowsAreIgnoredAndAbsorbTheirDetections) {
  // MOT15 10-column: the flag-0 box is not a miss, and a detection on it is not a false positive.
  const DetectionCounts c = eval_files("1,1,0,0,10,10,1,-1,-1,-1\n1,2,100,0,10,10,0,-1,-1,-1\n",
                                       "1,-1,0,0,10,10,1,-1,-1,-1\n1,-1,100,0,10,10,1,-1,-1,-1\n");
  EXPECT_EQ(c.ground_truth, 1u);
  EXPECT_EQ(c.ignored_ground_truth, 1u);
  EXPECT_EQ(c.true_positives, 1u);
  EXPECT_EQ(c.false_positives, 0u);
  EXPECT_EQ(c.false_negatives, 0u);
  EXPECT_EQ(c.discarded_detections, 1u);
  EXPECT_DOUBLE_EQ(c.precision(), 1.0);
}

TEST(DetectionMetrics, Mot16ClassAndVisibilityFilter) {
  // 9 columns: frame,id,x,y,w,h,flag,class,visibility.
  const std::string gt =
      "1,1,0,0,10,10,1,1,0.9\n"     // pedestrian, visible: counts
      "1,2,100,0,10,10,1,1,0.3\n"   // pedestrian, 30% visible: counts only when min-visibility <= 0.3
      "1,3,200,0,10,10,1,3,1.0\n"   // car: dropped (a detection on it is a false positive)
      "1,4,300,0,10,10,1,7,1.0\n";  // static person: ignored (absorbs a detection)
  const std::string det = "1,-1,0,0,10,10,1\n1,-1,200,0,10,10,1\n1,-1,300,0,10,10,1\n";
  const DetectionCounts all = eval_files(gt, det);
  EXPECT_EQ(all.ground_truth, 2u);
  EXPECT_EQ(all.true_positives, 1u);
  EXPECT_EQ(all.false_negatives, 1u);  // the 30%-visible pedestrian
  EXPECT_EQ(all.false_positives, 1u);  // the car
  DetectionEvalOptions half;
  half.min_visibility = 0.5;
  const DetectionCounts visible = eval_files(gt, det, half);
  EXPECT_EQ(visible.ground_truth, 1u);
  EXPECT_EQ(visible.true_positives, 1u);
  EXPECT_EQ(visible.false_negatives, 0u);
  EXPECT_EQ(visible.false_positives, 1u);
  EXPECT_DOUBLE_EQ(visible.moda(), 0.0);
}

TEST(DetectionMetrics, FormatDetectedFromColumns) {
  test::TempDir dir;
  test::write_text(dir / "a.txt", "1,1,0,0,10,10,1,1,0.5\n");
  test::write_text(dir / "b.txt", "1,1,0,0,10,10,1,-1,-1,-1\n");
  test::write_text(dir / "c.txt", "1,1,0,0,10,10\n");
  EXPECT_EQ(ground_truth_format(read_mot_file((dir / "a.txt").string(), true)), GroundTruthFormat::kMot16);
  EXPECT_EQ(ground_truth_format(read_mot_file((dir / "b.txt").string(), true)), GroundTruthFormat::kMot15);
  EXPECT_EQ(ground_truth_format(read_mot_file((dir / "c.txt").string(), true)), GroundTruthFormat::kPlain);
  // 9 columns whose visibility is not a fraction: an error naming file and line.
  test::write_text(dir / "bad.txt", "1,1,0,0,10,10,1,1,0.5\n2,1,0,0,10,10,1,1,7\n");
  try {
    read_mot_file((dir / "bad.txt").string(), true);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.txt:2"), std::string::npos) << e.what();
  }
}

TEST(DetectionMetrics, OptionsCheckNamesOption) {
  DetectionEvalOptions o;
  o.iou_threshold = 0;
  try {
    o.check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--iou"), std::string::npos);
  }
}

}  // namespace
}  // namespace crowdslam::people
