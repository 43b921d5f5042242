#include "crowdslam/viewer/messages.h"

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "crowdslam/io/jpeg_encode.h"

namespace crowdslam::viewer {

namespace {
nlohmann::json pose_json(const geometry::SE3& world_from_cam) {
  const auto& t = world_from_cam.translation();
  const auto& q = world_from_cam.rotation();
  return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
}

double round_to(double value, double step) { return std::round(value / step) * step; }
}  // namespace

std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    out += table[v >> 18];
    out += table[(v >> 12) & 63];
    out += table[(v >> 6) & 63];
    out += table[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = bytes[i] << 16;
    out += table[v >> 18];
    out += table[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = (bytes[i] << 16) | (bytes[i + 1] << 8);
    out += table[v >> 18];
    out += table[(v >> 12) & 63];
    out += table[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::string frame_json(const FrameStatus& s) {
  nlohmann::json j = {{"index", s.index},
                      {"timestamp", s.timestamp_s},
                      {"state", s.state},
                      {"method", s.method},
                      {"fps", round_to(s.fps, 0.1)},
                      {"tracking_ms", round_to(s.tracking_ms, 0.01)},
                      {"keypoints", s.keypoints},
                      {"tracked_points", s.tracked_points},
                      {"person_boxes", s.person_boxes},
                      {"people_area", round_to(s.people_area, 0.001)},
                      {"feature_budget", s.feature_budget},
                      {"keyframes", s.keyframes},
                      {"paused", s.paused}};
  j["pose"] = s.world_from_cam ? pose_json(*s.world_from_cam) : nlohmann::json(nullptr);
  return j.dump();
}

std::string image_json(size_t index, const cv::Mat& image, const std::vector<people::PersonBox>& boxes,
                       const std::vector<cv::KeyPoint>& kept, const std::vector<cv::KeyPoint>& removed,
                       int max_width) {
  const double scale = image.cols > max_width ? static_cast<double>(max_width) / image.cols : 1.0;
  cv::Mat small;
  if (scale < 1.0) {
    cv::resize(image, small, cv::Size(), scale, scale, cv::INTER_AREA);
  } else {
    small = image;
  }
  const std::vector<uint8_t> jpeg = io::encode_jpeg(small, 70);
  nlohmann::json j = {{"index", index}, {"width", small.cols}, {"height", small.rows}};
  j["jpeg"] = base64(jpeg);
  nlohmann::json b = nlohmann::json::array();
  for (const auto& box : boxes) {
    b.push_back({round_to(box.box.x * scale, 0.1), round_to(box.box.y * scale, 0.1),
                 round_to(box.box.width * scale, 0.1), round_to(box.box.height * scale, 0.1)});
  }
  j["boxes"] = b;
  const auto points = [&](const std::vector<cv::KeyPoint>& keys) {
    std::vector<double> flat;
    flat.reserve(keys.size() * 2);
    for (const auto& k : keys) {
      flat.push_back(round_to(k.pt.x * scale, 0.1));
      flat.push_back(round_to(k.pt.y * scale, 0.1));
    }
    return flat;
  };
  j["kept"] = points(kept);
  j["removed"] = points(removed);
  return j.dump();
}

std::string map_json(const system::MapSnapshot& snapshot) {
  std::vector<uint64_t> ids;
  std::vector<long> xyz;  // millimetres
  std::vector<int> observations;
  ids.reserve(snapshot.points.size());
  xyz.reserve(3 * snapshot.points.size());
  for (const auto& p : snapshot.points) {
    ids.push_back(p.id);
    xyz.push_back(std::lround(p.x * 1000.0));
    xyz.push_back(std::lround(p.y * 1000.0));
    xyz.push_back(std::lround(p.z * 1000.0));
    observations.push_back(p.observations);
  }
  nlohmann::json keyframes = nlohmann::json::array();
  for (const auto& kf : snapshot.keyframes) keyframes.push_back({{"id", kf.id}, {"pose", pose_json(kf.world_from_cam)}});
  nlohmann::json edges = nlohmann::json::array();
  for (const auto& [a, b] : snapshot.covisibility) edges.push_back({a, b});
  nlohmann::json loops = nlohmann::json::array();
  for (const auto& [a, b] : snapshot.loop_edges) loops.push_back({a, b});
  return nlohmann::json({{"frame", snapshot.frame_index},
                         {"map_id", snapshot.map_id},
                         {"point_ids", ids},
                         {"points_mm", xyz},
                         {"observations", observations},
                         {"keyframes", keyframes},
                         {"covisibility", edges},
                         {"loop_edges", loops},
                         {"loops_closed", snapshot.loops_closed}})
      .dump();
}

std::string ground_truth_json(const io::Trajectory& ground_truth, const geometry::Similarity& alignment,
                              size_t max_points) {
  const size_t step = std::max<size_t>(1, ground_truth.size() / std::max<size_t>(1, max_points));
  std::vector<double> flat;
  for (size_t i = 0; i < ground_truth.size(); i += step) {
    const geometry::Vec3 p = alignment.apply(ground_truth[i].world_from_cam.translation());
    flat.push_back(round_to(p.x(), 0.001));
    flat.push_back(round_to(p.y(), 0.001));
    flat.push_back(round_to(p.z(), 0.001));
  }
  return nlohmann::json({{"positions", flat}}).dump();
}

std::string trajectory_json(const io::Trajectory& trajectory) {
  std::vector<double> flat;
  flat.reserve(3 * trajectory.size());
  for (const auto& pose : trajectory) {
    const auto& t = pose.world_from_cam.translation();
    flat.push_back(round_to(t.x(), 0.0001));
    flat.push_back(round_to(t.y(), 0.0001));
    flat.push_back(round_to(t.z(), 0.0001));
  }
  return nlohmann::json({{"positions", flat}}).dump();
}

std::optional<geometry::Similarity> align_ground_truth(const io::Trajectory& ground_truth,
                                                      const std::vector<std::pair<double, geometry::Vec3>>& estimate,
                                                      bool with_scale, size_t min_pairs) {
  if (ground_truth.empty()) return std::nullopt;
  std::vector<geometry::Vec3> source, target;
  size_t g = 0;
  for (const auto& [stamp, position] : estimate) {
    while (g + 1 < ground_truth.size() &&
           std::abs(ground_truth[g + 1].timestamp_s - stamp) <= std::abs(ground_truth[g].timestamp_s - stamp)) {
      ++g;
    }
    if (std::abs(ground_truth[g].timestamp_s - stamp) > 0.02) continue;
    source.push_back(ground_truth[g].world_from_cam.translation());
    target.push_back(position);
  }
  if (source.size() < min_pairs) return std::nullopt;
  Eigen::Matrix3Xd s(3, static_cast<Eigen::Index>(source.size())), t(3, static_cast<Eigen::Index>(target.size()));
  for (size_t i = 0; i < source.size(); ++i) {
    s.col(static_cast<Eigen::Index>(i)) = source[i];
    t.col(static_cast<Eigen::Index>(i)) = target[i];
  }
  return geometry::align_umeyama(s, t, with_scale);
}

}  // namespace crowdslam::viewer
