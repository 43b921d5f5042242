#include "synth_test_util.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "test_support.h"

namespace crowdslam::synth::test {
namespace {

double grey_at(const cv::Mat& colour, double u, double v) {
  const int x0 = static_cast<int>(std::floor(u));
  const int y0 = static_cast<int>(std::floor(v));
  const double fx = u - x0;
  const double fy = v - y0;
  double sum = 0.0;
  for (int dy = 0; dy < 2; ++dy) {
    for (int dx = 0; dx < 2; ++dx) {
      const cv::Vec3b c = colour.at<cv::Vec3b>(y0 + dy, x0 + dx);
      const double w = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);
      sum += w * (c[0] + c[1] + c[2]) / 3.0;
    }
  }
  return sum;
}

}  // namespace

Consistency check_consistency(const cv::Mat& colour_i, const cv::Mat& depth_i, const cv::Mat& label_i,
                              const geometry::SE3& world_from_i, const cv::Mat& colour_j, const cv::Mat& depth_j,
                              const cv::Mat& label_j, const geometry::SE3& world_from_j, const Intrinsics& k,
                              int step) {
  Consistency result;
  const geometry::SE3 j_from_i = world_from_j.inverse() * world_from_i;
  std::vector<double> diffs;
  for (int v = 0; v < depth_i.rows; v += step) {
    for (int u = 0; u < depth_i.cols; u += step) {
      const double d = depth_i.at<float>(v, u);
      if (d <= 0.0 || (!label_i.empty() && label_i.at<std::uint16_t>(v, u) != 0)) continue;
      ++result.sampled;
      const Eigen::Vector3d p_i(d * (u - k.cx) / k.fx, d * (v - k.cy) / k.fy, d);
      const Eigen::Vector3d p_j = j_from_i * p_i;
      if (p_j.z() <= 0.05) continue;
      const double uj = k.fx * p_j.x() / p_j.z() + k.cx;
      const double vj = k.fy * p_j.y() / p_j.z() + k.cy;
      if (uj < 0.0 || vj < 0.0 || uj >= k.width - 1.0 || vj >= k.height - 1.0) continue;
      ++result.inside;
      const int nu = static_cast<int>(std::lround(uj));
      const int nv = static_cast<int>(std::lround(vj));
      if (!label_j.empty() && label_j.at<std::uint16_t>(nv, nu) != 0) continue;
      const double dj = depth_j.at<float>(nv, nu);
      if (std::abs(dj - p_j.z()) > 0.01 * p_j.z()) continue;
      ++result.depth_agrees;
      const cv::Vec3b c = colour_i.at<cv::Vec3b>(v, u);
      diffs.push_back(std::abs((c[0] + c[1] + c[2]) / 3.0 - grey_at(colour_j, uj, vj)));
    }
  }
  if (!diffs.empty()) {
    std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
    result.median_grey_diff = diffs[diffs.size() / 2];
  }
  return result;
}

bool test_sprite_opaque(int x, int y) {
  const bool head = (x - 30) * (x - 30) + (y - 14) * (y - 14) <= 12 * 12;
  const bool neck = x >= 25 && x < 35 && y >= 24 && y < 30;
  const bool torso = x >= 10 && x < 50 && y >= 28 && y < 92;
  const bool arms = (x >= 2 && x < 10 && y >= 30 && y < 86) || (x >= 50 && x < 58 && y >= 30 && y < 86);
  const bool legs = ((x >= 13 && x < 28) || (x >= 32 && x < 47)) && y >= 92 && y < 160;
  return head || neck || torso || arms || legs;
}

void write_test_sprites(const std::filesystem::path& dir, int count, bool opaque_rectangles) {
  std::filesystem::create_directories(dir);
  nlohmann::json list{{"generator", "test"}, {"count", count}, {"sprites", nlohmann::json::array()}};
  for (int i = 0; i < count; ++i) {
    cv::Mat sprite(160, 60, CV_8UC4, cv::Scalar::all(0));
    const cv::Vec3b shirt((37 * i + 40) % 256, (91 * i + 120) % 256, (53 * i + 200) % 256);
    const cv::Vec3b trousers((29 * i + 30) % 128, (17 * i + 20) % 128, (43 * i + 60) % 128);
    for (int y = 0; y < sprite.rows; ++y) {
      for (int x = 0; x < sprite.cols; ++x) {
        if (!opaque_rectangles && !test_sprite_opaque(x, y)) continue;
        const cv::Vec3b c = y < 28 ? cv::Vec3b(120, 160, 210) : (y < 92 ? shirt : trousers);
        const uchar grain = static_cast<uchar>(((x * 7 + y * 13) % 5) * 8);  // some texture for corners
        sprite.at<cv::Vec4b>(y, x) = cv::Vec4b(cv::saturate_cast<uchar>(c[0] + grain), c[1], c[2], 255);
      }
    }
    const std::string name = "test_" + std::to_string(i) + ".png";
    cv::imwrite((dir / name).string(), sprite);
    list["sprites"].push_back({{"file", name},
                               {"sequence", "test"},
                               {"frame", 1},
                               {"id", i + 1},
                               {"width", 60},
                               {"height", 160},
                               {"fill", 0.6},
                               {"facing", 1}});
  }
  crowdslam::test::write_text(dir / "sprites.json", list.dump(2));
}

}  // namespace crowdslam::synth::test
