#include "crowdslam/people/detection_metrics.h"

#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "crowdslam/people/assignment.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double ratio(double num, double den) { return den > 0 ? num / den : kNaN; }

enum class GtRole { kCounts, kIgnored, kDropped };

GtRole role_of(const MotRow& row, GroundTruthFormat format, double min_visibility) {
  if (row.score == 0) return GtRole::kIgnored;
  if (format != GroundTruthFormat::kMot16) return GtRole::kCounts;
  switch (row.object_class) {
    case 1:
      return row.visibility < min_visibility ? GtRole::kIgnored : GtRole::kCounts;
    case 2:
    case 7:
    case 8:
    case 12:
      return GtRole::kIgnored;
    default:
      return GtRole::kDropped;
  }
}

struct FrameBoxesByRole {
  std::vector<cv::Rect2f> counted, ignored, detections;
};

std::vector<std::vector<double>> iou_matrix(const std::vector<cv::Rect2f>& rows,
                                            const std::vector<cv::Rect2f>& cols) {
  std::vector<std::vector<double>> m(rows.size(), std::vector<double>(cols.size()));
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < cols.size(); ++c) m[r][c] = box_iou(rows[r], cols[c]);
  return m;
}

}  // namespace

void DetectionEvalOptions::check() const {
  auto fail = [](const char* key, double value, const char* expected) {
    std::ostringstream s;
    s << key << " must be " << expected << ", got " << value;
    throw InputError(s.str());
  };
  if (!(iou_threshold > 0 && iou_threshold <= 1)) fail("--iou", iou_threshold, "in (0, 1]");
  if (!(min_visibility >= 0 && min_visibility <= 1)) fail("--min-visibility", min_visibility, "in [0, 1]");
}

double DetectionCounts::precision() const {
  return ratio(static_cast<double>(true_positives), static_cast<double>(true_positives + false_positives));
}
double DetectionCounts::recall() const {
  return ratio(static_cast<double>(true_positives), static_cast<double>(true_positives + false_negatives));
}
double DetectionCounts::moda() const {
  if (ground_truth == 0) return kNaN;
  return 1.0 - static_cast<double>(false_negatives + false_positives) / static_cast<double>(ground_truth);
}
double DetectionCounts::modp() const { return ratio(iou_sum, static_cast<double>(true_positives)); }

const char* to_string(GroundTruthFormat format) {
  switch (format) {
    case GroundTruthFormat::kMot15:
      return "mot15";
    case GroundTruthFormat::kMot16:
      return "mot16";
    case GroundTruthFormat::kPlain:
      break;
  }
  return "plain";
}

GroundTruthFormat ground_truth_format(const MotFile& ground_truth) {
  if (ground_truth.columns == 9) return GroundTruthFormat::kMot16;
  if (ground_truth.columns >= 10) return GroundTruthFormat::kMot15;
  if (ground_truth.columns == 8)
    throw input_error(ground_truth.path,
                      "8-column ground truth is not a MOT format (expected 6, 7, 9 or 10)");
  return GroundTruthFormat::kPlain;
}

void evaluate_frame(const std::vector<cv::Rect2f>& counted, const std::vector<cv::Rect2f>& ignored,
                    const std::vector<cv::Rect2f>& detections, double iou_threshold,
                    DetectionCounts& counts) {
  const std::vector<std::vector<double>> iou = iou_matrix(counted, detections);
  const std::vector<int> match = match_by_similarity(iou, iou_threshold);
  std::vector<char> det_matched(detections.size(), 0);
  for (std::size_t g = 0; g < counted.size(); ++g) {
    if (match[g] < 0) {
      ++counts.false_negatives;
      continue;
    }
    ++counts.true_positives;
    counts.iou_sum += iou[g][static_cast<std::size_t>(match[g])];
    det_matched[static_cast<std::size_t>(match[g])] = 1;
  }
  std::vector<cv::Rect2f> left;
  for (std::size_t d = 0; d < detections.size(); ++d)
    if (!det_matched[d]) left.push_back(detections[d]);
  std::size_t discarded = 0;
  if (!ignored.empty() && !left.empty()) {
    for (int m : match_by_similarity(iou_matrix(ignored, left), iou_threshold))
      if (m >= 0) ++discarded;
  }
  counts.discarded_detections += discarded;
  counts.false_positives += left.size() - discarded;
  counts.ground_truth += counted.size();
  counts.ignored_ground_truth += ignored.size();
  counts.detections += detections.size();
}

DetectionCounts evaluate_detections(const MotFile& ground_truth, const MotFile& detections,
                                    const DetectionEvalOptions& options) {
  options.check();
  const GroundTruthFormat format = ground_truth_format(ground_truth);
  std::map<int, FrameBoxesByRole> frames;
  for (const MotRow& row : ground_truth.rows) {
    switch (role_of(row, format, options.min_visibility)) {
      case GtRole::kCounts:
        frames[row.frame].counted.push_back(row.box);
        break;
      case GtRole::kIgnored:
        frames[row.frame].ignored.push_back(row.box);
        break;
      case GtRole::kDropped:
        break;
    }
  }
  for (const MotRow& row : detections.rows) frames[row.frame].detections.push_back(row.box);
  DetectionCounts counts;
  for (const auto& [frame, boxes] : frames) {
    evaluate_frame(boxes.counted, boxes.ignored, boxes.detections, options.iou_threshold, counts);
    ++counts.frames;
  }
  return counts;
}

}  // namespace crowdslam::people
