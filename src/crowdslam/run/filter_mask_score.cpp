#include "crowdslam/run/filter_mask_score.h"

#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "crowdslam/io/image_check.h"
#include "crowdslam/util/error.h"

namespace crowdslam::run {

FilterMaskScore::FilterMaskScore(std::filesystem::path mask_dir) : mask_dir_(std::move(mask_dir)) {
  std::error_code ec;
  if (!std::filesystem::is_directory(mask_dir_, ec)) {
    throw input_error(mask_dir_.string(),
                      "no person masks here (--score-filter reads DATASET/people_mask, "
                      "as `crowdslam synth` writes it)");
  }
}

void FilterMaskScore::on_frame(const system::FrameReport& report,
                               const std::optional<geometry::SE3>& /*pose*/,
                               const io::FrameImages& /*images*/) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu.png", report.index);
  const std::filesystem::path path = mask_dir_ / name;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    ++counts_.frames_without_mask;
    return;
  }
  const cv::Mat stored = io::read_mask_image(path.string());
  cv::Mat person;  // 255 on a person
  cv::compare(stored, 0, person, cv::CMP_GT);
  cv::Mat near;  // 255 within kEdgeRadiusPx of a person (a square window)
  cv::dilate(person, near, cv::Mat::ones(2 * kEdgeRadiusPx + 1, 2 * kEdgeRadiusPx + 1, CV_8U));
  ++counts_.frames_scored;
  enum Where { kOutside, kPerson, kEdge, kBackground };
  auto where = [&](const cv::KeyPoint& k) {
    const int x = cvRound(k.pt.x);
    const int y = cvRound(k.pt.y);
    if (x < 0 || y < 0 || x >= person.cols || y >= person.rows) return kOutside;
    if (person.at<uint8_t>(y, x) != 0) return kPerson;
    return near.at<uint8_t>(y, x) != 0 ? kEdge : kBackground;
  };
  auto count = [&](const std::vector<cv::KeyPoint>& keys, size_t& on_people, size_t& on_edges,
                   size_t& on_background) {
    for (const auto& k : keys) {
      switch (where(k)) {
        case kOutside:
          ++counts_.outside_mask;
          break;
        case kPerson:
          ++on_people;
          break;
        case kEdge:
          ++on_edges;
          break;
        case kBackground:
          ++on_background;
          break;
      }
    }
  };
  count(report.kept_keypoints, counts_.kept_on_people, counts_.kept_on_edges, counts_.kept_on_background);
  count(report.removed_keypoints, counts_.removed_on_people, counts_.removed_on_edges,
        counts_.removed_on_background);
}

nlohmann::json FilterMaskScore::to_json() const {
  const FilterMaskCounts& c = counts_;
  auto ratio = [](size_t a, size_t b) -> nlohmann::json {
    return b == 0 ? nlohmann::json() : nlohmann::json(static_cast<double>(a) / static_cast<double>(b));
  };
  const size_t people = c.kept_on_people + c.removed_on_people;
  const size_t background = c.kept_on_background + c.removed_on_background;
  const size_t kept = c.kept_on_people + c.kept_on_edges + c.kept_on_background;
  return {{"mask_dir", mask_dir_.string()},
          {"frames_scored", c.frames_scored},
          {"frames_without_mask", c.frames_without_mask},
          {"edge_radius_px", kEdgeRadiusPx},
          {"kept_on_people", c.kept_on_people},
          {"kept_on_edges", c.kept_on_edges},
          {"kept_on_background", c.kept_on_background},
          {"removed_on_people", c.removed_on_people},
          {"removed_on_edges", c.removed_on_edges},
          {"removed_on_background", c.removed_on_background},
          {"outside_mask", c.outside_mask},
          {"people_removed", ratio(c.removed_on_people, people)},
          {"background_kept", ratio(c.kept_on_background, background)},
          {"kept_on_people_share", ratio(c.kept_on_people + c.kept_on_edges, kept)}};
}

}  // namespace crowdslam::run
