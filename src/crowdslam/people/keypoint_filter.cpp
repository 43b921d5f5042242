#include "crowdslam/people/keypoint_filter.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "crowdslam/people/box_depth.h"
#include "crowdslam/people/person_segment.h"
#include "crowdslam/util/error.h"

namespace crowdslam::people {

FilterMode parse_filter_mode(const std::string& name, const std::string& key) {
  if (name == "paper") return FilterMode::kPaper;
  if (name == "depth") return FilterMode::kDepth;
  throw InputError(key + ": unknown people filter mode '" + name + "' (expected paper or depth)");
}

const char* to_string(FilterMode mode) { return mode == FilterMode::kPaper ? "paper" : "depth"; }

void KeypointFilterOptions::check() const {
  if (!(margin_px >= 0))
    throw InputError("PeopleFilter.margin_px must be >= 0, got " + std::to_string(margin_px));
  if (!(depth_margin_m >= 0)) {
    throw InputError("PeopleFilter.depth_margin_m must be >= 0, got " + std::to_string(depth_margin_m));
  }
}

namespace {

// A keypoint this close to the person's surface is on their outline (the middle of the ORB patch).
constexpr int kSegmentRadiusPx = 8;

// Whether the keypoint's 5 x 5 neighbourhood shows the person: a depth within `margin_m` of `person_m`.
// Such a keypoint is behind the person at its centre pixel but on their outline, and its descriptor sees
// the person's edge and moves with them.
bool on_silhouette(const cv::Mat& depth_image_raw, double depth_factor, const cv::KeyPoint& k, double person_m,
                   double margin_m, int kRadius) {
  if (depth_image_raw.empty() || depth_image_raw.type() != CV_16UC1) return false;
  const cv::Rect region = cv::Rect(cvRound(k.pt.x) - kRadius, cvRound(k.pt.y) - kRadius, 2 * kRadius + 1,
                                   2 * kRadius + 1) &
                          cv::Rect(0, 0, depth_image_raw.cols, depth_image_raw.rows);
  const double low = (person_m - margin_m) * depth_factor;
  const double high = (person_m + margin_m) * depth_factor;
  for (int y = region.y; y < region.y + region.height; ++y) {
    const auto* row = depth_image_raw.ptr<uint16_t>(y);
    for (int x = region.x; x < region.x + region.width; ++x) {
      if (row[x] > 0 && row[x] >= low && row[x] <= high) return true;
    }
  }
  return false;
}

}  // namespace

double estimate_person_depth(const cv::Mat& depth_image_raw, double depth_factor, const cv::Rect2f& box,
                             double quantile) {
  if (depth_image_raw.empty() || depth_image_raw.type() != CV_16UC1) return -1.0;
  // Central region: half the width, 70% of the height.
  const cv::Rect2f centre(box.x + 0.25f * box.width, box.y + 0.15f * box.height, 0.5f * box.width,
                          0.7f * box.height);
  const cv::Rect region =
      cv::Rect(cv::Point(cvFloor(centre.x), cvFloor(centre.y)),
               cv::Point(cvCeil(centre.x + centre.width), cvCeil(centre.y + centre.height))) &
      cv::Rect(0, 0, depth_image_raw.cols, depth_image_raw.rows);
  if (region.area() <= 0) return -1.0;
  std::vector<uint16_t> values = sample_valid_depths(depth_image_raw, region, 2000);
  if (values.size() < 10) return -1.0;
  const auto last = static_cast<long>(values.size()) - 1;
  const auto nth =
      values.begin() + std::min(static_cast<long>(values.size() * std::clamp(quantile, 0.0, 1.0)), last);
  std::nth_element(values.begin(), nth, values.end());
  return *nth / depth_factor;
}

FilterResult filter_keypoints(const std::vector<cv::KeyPoint>& keypoints, const std::vector<PersonBox>& boxes,
                              const KeypointFilterOptions& options, const std::vector<float>& depth_m,
                              const cv::Mat& depth_image_raw, double depth_factor) {
  FilterResult result;
  result.keep.assign(keypoints.size(), true);
  result.box.assign(keypoints.size(), -1);
  if (boxes.empty()) return result;
  const float margin = static_cast<float>(options.margin_px);
  std::vector<cv::Rect2f> grown;
  std::vector<int> origin;  // index in `boxes` of each grown box
  grown.reserve(boxes.size());
  for (size_t k = 0; k < boxes.size(); ++k) {
    const PersonBox& b = boxes[k];
    // Zero, negative or non-finite boxes are ignored (NaN fails every comparison, so check explicitly).
    if (!(b.box.width > 0) || !(b.box.height > 0) || !std::isfinite(b.box.x) || !std::isfinite(b.box.y) ||
        !std::isfinite(b.box.width) || !std::isfinite(b.box.height)) {
      continue;
    }
    grown.emplace_back(b.box.x - margin, b.box.y - margin, b.box.width + 2 * margin,
                       b.box.height + 2 * margin);
    origin.push_back(static_cast<int>(k));
    if (options.mode == FilterMode::kDepth) {
      result.person_depth_m.push_back(
          estimate_person_depth(depth_image_raw, depth_factor, b.box, options.person_depth_quantile));
    }
  }
  const bool use_depth = options.mode == FilterMode::kDepth && depth_m.size() == keypoints.size();
  // Each box's surface, made when first needed (nothing is allocated with the rule off, on every frame).
  std::vector<std::optional<PersonSegment>> segments;
  if (options.segment_from_m > 0) segments.resize(grown.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::Point2f& p = keypoints[i].pt;
    for (size_t b = 0; b < grown.size(); ++b) {
      const cv::Rect2f& r = grown[b];
      if (p.x < r.x || p.y < r.y || p.x >= r.x + r.width || p.y >= r.y + r.height) continue;
      if (use_depth) {
        const double person = result.person_depth_m[b];
        // Clearly behind the person, and not on their outline: background seen past them, keep (it may
        // still be in another box).
        // Background close behind the person (within two margins) is kept only clear of their outline
        // by the middle of the ORB patch (8 px): next to the person it is mostly their edge.
        const int radius = depth_m[i] > person + 2 * options.depth_margin_m ? 2 : 8;
        if (person > 0 && depth_m[i] > person + options.depth_margin_m &&
            !(options.silhouettes &&
              on_silhouette(depth_image_raw, depth_factor, keypoints[i], person, options.depth_margin_m, radius)))
          continue;
        // Close behind the person but off their surface: what the box took in behind them.
        if (options.segment_from_m > 0 && person > 0 && depth_m[i] > person + options.segment_from_m) {
          if (!segments[b]) {
            PersonSegmentOptions segment_options;
            segment_options.seed_behind_m = options.segment_from_m;
            segments[b].emplace(depth_image_raw, depth_factor, boxes[static_cast<size_t>(origin[b])].box,
                                person, options.depth_margin_m, segment_options);
          }
          if (segments[b]->cells() > 0 && !segments[b]->near(p, kSegmentRadiusPx)) continue;
        }
      }
      result.keep[i] = false;
      result.box[i] = origin[b];
      ++result.removed;
      break;
    }
  }
  return result;
}

}  // namespace crowdslam::people
