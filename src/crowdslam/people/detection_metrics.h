#pragma once
// Detection metrics of the Crowd-SLAM paper (Eqs. 1-4; CLEAR MOD metrics of Kasturi et al.):
//   precision = TP / (TP + FP),  recall = TP / (TP + FN),
//   MODA = 1 - (FN + FP) / N_gt,  MODP = (sum of IoU over matched pairs) / (number of matched pairs),
// pooled over every frame of the sequence (MODP is the mean IoU of all matched pairs).
//
// Matching, per frame: ground-truth boxes that count vs all detections, the assignment maximising the
// number of pairs with IoU >= iou_threshold and then their total IoU (Hungarian, assignment.h).
// Which ground truth counts:
//   - rows with flag (column 7) 0 are ignored;
//   - 9-column MOT16/17 ground truth: only class 1 (pedestrian) counts, and pedestrians with visibility
//     < min_visibility are ignored; classes 2, 7, 8, 12 (person on vehicle, static person, distractor,
//     reflection) are ignored; other classes (vehicles, objects) are dropped;
//   - 6/7/10-column ground truth (MOT15: columns 8-10 are world x, y, z) has no class or visibility.
// Ignored boxes follow the MOTChallenge devkit: a detection left unmatched after the first matching that
// overlaps an ignored box (IoU >= threshold, one-to-one) is discarded: neither TP nor FP.
// Undefined ratios (0 / 0) are NaN.
#include <cstddef>
#include <string>
#include <vector>

#include "crowdslam/people/mot_format.h"

namespace crowdslam::people {

struct DetectionEvalOptions {
  double iou_threshold = 0.5;
  double min_visibility = 0.0;  // 9-column ground truth only

  void check() const;  // throws InputError naming the bad value
};

struct DetectionCounts {
  std::size_t frames = 0;        // frames with any ground truth or detection
  std::size_t ground_truth = 0;  // N_gt: boxes that count
  std::size_t ignored_ground_truth = 0;
  std::size_t detections = 0;            // all detection rows
  std::size_t discarded_detections = 0;  // matched to ignored ground truth
  std::size_t true_positives = 0;
  std::size_t false_positives = 0;
  std::size_t false_negatives = 0;
  double iou_sum = 0.0;  // over the true positives

  [[nodiscard]] double precision() const;
  [[nodiscard]] double recall() const;
  [[nodiscard]] double moda() const;
  [[nodiscard]] double modp() const;
};

enum class GroundTruthFormat { kPlain, kMot15, kMot16 };
// "plain" (6 or 7 columns), "mot15" (10 columns), "mot16" (9 columns: class, visibility).
const char* to_string(GroundTruthFormat format);
GroundTruthFormat ground_truth_format(const MotFile& ground_truth);

// One frame's worth: which ground-truth boxes count and which are ignored (already filtered), and the
// detections. Adds the frame's TP/FP/FN to `counts`.
void evaluate_frame(const std::vector<cv::Rect2f>& counted, const std::vector<cv::Rect2f>& ignored,
                    const std::vector<cv::Rect2f>& detections, double iou_threshold, DetectionCounts& counts);

// Whole sequence from the two files (read with read_mot_file(gt, true) and read_mot_file(det)).
DetectionCounts evaluate_detections(const MotFile& ground_truth, const MotFile& detections,
                                    const DetectionEvalOptions& options);

}  // namespace crowdslam::people
