#include "crowdslam/people/box_flow.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <string>

#include "crowdslam/util/error.h"

namespace crowdslam::people {
namespace {

double median(std::vector<double>& values) {
  const auto mid = values.begin() + static_cast<long>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  double m = *mid;
  if (values.size() % 2 == 0) m = 0.5 * (m + *std::max_element(values.begin(), mid));
  return m;
}

cv::Rect integer_rect(const cv::Rect2f& box, const cv::Size& size) {
  return cv::Rect(cv::Point(std::max(0, cvFloor(box.x)), std::max(0, cvFloor(box.y))),
                  cv::Point(std::min(size.width, cvCeil(box.x + box.width)),
                            std::min(size.height, cvCeil(box.y + box.height))));
}

}  // namespace

void BoxFlowOptions::check() const {
  if (max_points_per_box < 1) throw InputError("box flow: max_points_per_box must be >= 1");
  if (min_points < 1) throw InputError("box flow: min_points must be >= 1");
  if (!(forward_backward_px > 0)) throw InputError("box flow: forward_backward_px must be > 0");
  if (window < 5 || levels < 0) throw InputError("box flow: window must be >= 5 and levels >= 0");
}

void seed_points(const cv::Mat& gray, std::vector<FlowBox>& boxes, const BoxFlowOptions& options) {
  CV_Assert(gray.type() == CV_8UC1);
  for (FlowBox& b : boxes) {
    b.points.clear();
    const cv::Rect roi = integer_rect(b.box.box, gray.size());
    if (roi.width < 8 || roi.height < 8) continue;
    // Corners at least ~1/8 of the smaller side apart spread over the whole person.
    const double min_distance = std::max(3.0, std::min(roi.width, roi.height) / 8.0);
    std::vector<cv::Point2f> corners;
    cv::goodFeaturesToTrack(gray(roi), corners, options.max_points_per_box, 0.01, min_distance);
    for (const auto& c : corners) b.points.emplace_back(c.x + roi.x, c.y + roi.y);
  }
}

FlowImage make_flow_image(const cv::Mat& gray, const BoxFlowOptions& options) {
  CV_Assert(gray.type() == CV_8UC1);
  FlowImage image;
  image.gray = gray;
  cv::buildOpticalFlowPyramid(gray, image.pyramid, cv::Size(options.window, options.window), options.levels);
  return image;
}

cv::Rect2f follow_motion(const cv::Rect2f& box, const cv::Point2f& leader_centre, const BoxMotion& motion,
                         int width, int height) {
  if (motion.left_image) return {};
  if (!motion.moved) return box;
  const double cx = leader_centre.x + motion.dx + motion.scale * (box.x + 0.5 * box.width - leader_centre.x);
  const double cy = leader_centre.y + motion.dy + motion.scale * (box.y + 0.5 * box.height - leader_centre.y);
  const double w = box.width * motion.scale;
  const double h = box.height * motion.scale;
  return clip_box(cv::Rect2f(static_cast<float>(cx - 0.5 * w), static_cast<float>(cy - 0.5 * h),
                             static_cast<float>(w), static_cast<float>(h)),
                  width, height);
}

FlowStats move_boxes(const cv::Mat& from, const cv::Mat& to, std::vector<FlowBox>& boxes,
                     const BoxFlowOptions& options) {
  CV_Assert(from.type() == CV_8UC1 && to.type() == CV_8UC1 && from.size() == to.size());
  return move_boxes(make_flow_image(from, options), make_flow_image(to, options), boxes, options);
}

FlowStats move_boxes(const FlowImage& from_image, const FlowImage& to_image, std::vector<FlowBox>& boxes,
                     const BoxFlowOptions& options, std::vector<BoxMotion>* motions) {
  const cv::Mat& from = from_image.gray;
  const cv::Mat& to = to_image.gray;
  CV_Assert(from.type() == CV_8UC1 && to.type() == CV_8UC1 && from.size() == to.size());
  if (motions != nullptr) motions->assign(boxes.size(), BoxMotion{});
  FlowStats stats;
  std::vector<cv::Point2f> start;
  for (const FlowBox& b : boxes) start.insert(start.end(), b.points.begin(), b.points.end());
  std::vector<cv::Point2f> forward, backward;
  std::vector<unsigned char> ok_forward, ok_backward;
  std::vector<float> error;
  if (!start.empty()) {
    const cv::Size window(options.window, options.window);
    const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.03);
    cv::calcOpticalFlowPyrLK(from_image.pyramid, to_image.pyramid, start, forward, ok_forward, error, window,
                             options.levels, stop);
    cv::calcOpticalFlowPyrLK(to_image.pyramid, from_image.pyramid, forward, backward, ok_backward, error, window,
                             options.levels, stop);
  }
  const float width = static_cast<float>(to.cols);
  const float height = static_cast<float>(to.rows);
  std::vector<FlowBox> moved;
  moved.reserve(boxes.size());
  std::size_t offset = 0;
  for (std::size_t index = 0; index < boxes.size(); ++index) {
    FlowBox& b = boxes[index];
    std::vector<cv::Point2f> before, after;
    for (std::size_t i = offset; i < offset + b.points.size(); ++i) {
      if (!ok_forward[i] || !ok_backward[i]) continue;
      if (cv::norm(backward[i] - start[i]) > options.forward_backward_px) continue;
      before.push_back(start[i]);
      after.push_back(forward[i]);
    }
    offset += b.points.size();
    if (static_cast<int>(after.size()) < options.min_points) {
      ++stats.boxes_kept;
      moved.push_back(std::move(b));  // stays where it was; its corners did not survive
      moved.back().points = after;
      continue;
    }
    std::vector<double> dx, dy, ratio;
    for (std::size_t i = 0; i < after.size(); ++i) {
      dx.push_back(after[i].x - before[i].x);
      dy.push_back(after[i].y - before[i].y);
    }
    // Scale: median over pairs of corners of (distance after / distance before); pairs closer than
    // 2 px say nothing about scale. At most ~300 pairs (i, i + k) so this stays cheap.
    const std::size_t n = after.size();
    for (std::size_t k = 1; k < n && ratio.size() < 300; ++k) {
      for (std::size_t i = 0; i + k < n && ratio.size() < 300; i += 1) {
        const double d0 = cv::norm(before[i] - before[i + k]);
        if (d0 < 2.0) continue;
        ratio.push_back(cv::norm(after[i] - after[i + k]) / d0);
      }
    }
    const double tx = median(dx);
    const double ty = median(dy);
    const double scale = ratio.empty() ? 1.0 : std::clamp(median(ratio), 0.5, 2.0);
    const cv::Rect2f& r = b.box.box;
    const double cx = r.x + 0.5 * r.width + tx;
    const double cy = r.y + 0.5 * r.height + ty;
    const double w = r.width * scale;
    const double h = r.height * scale;
    b.box.box = clip_box(cv::Rect2f(static_cast<float>(cx - 0.5 * w), static_cast<float>(cy - 0.5 * h),
                                    static_cast<float>(w), static_cast<float>(h)),
                         to.cols, to.rows);
    if (motions != nullptr) (*motions)[index] = BoxMotion{true, false, tx, ty, scale};
    if (!(b.box.box.width > 0) || !(b.box.box.height > 0)) {  // left the image
      if (motions != nullptr) (*motions)[index] = BoxMotion{false, true, tx, ty, scale};
      continue;
    }
    b.points.clear();
    for (const auto& p : after) {
      if (p.x >= 0 && p.y >= 0 && p.x < width && p.y < height) b.points.push_back(p);
    }
    ++stats.boxes_moved;
    moved.push_back(std::move(b));
  }
  boxes = std::move(moved);
  return stats;
}

std::vector<FlowBox> to_flow_boxes(const std::vector<PersonBox>& boxes) {
  std::vector<FlowBox> out;
  out.reserve(boxes.size());
  for (const auto& b : boxes) out.push_back(FlowBox{b, {}, -1});
  return out;
}

std::vector<PersonBox> to_person_boxes(const std::vector<FlowBox>& boxes) {
  std::vector<PersonBox> out;
  out.reserve(boxes.size());
  for (const auto& b : boxes) out.push_back(b.box);
  return out;
}

}  // namespace crowdslam::people
