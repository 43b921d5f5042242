// Finding and loading person sprites (sprites.h).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "crowdslam/io/opencv_extras.h"
#include "crowdslam/synth/sprites.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/project_paths.h"
#include "crowdslam/util/text.h"


namespace crowdslam::synth {
namespace fs = std::filesystem;
namespace {

constexpr int kFillPasses = 12;

// Colour for the transparent texels: each pass gives a transparent texel next to filled ones the mean of
// those neighbours; whatever is left after kFillPasses gets the mean opaque colour. Filtering (bilinear,
// mip levels) near the silhouette then blends with the person's own colours, not with black.
cv::Mat fill_transparent(const cv::Mat& bgra) {
  cv::Mat colour(bgra.size(), CV_8UC3);
  cv::Mat known(bgra.size(), CV_8U);
  cv::Vec3d sum(0, 0, 0);
  int opaque = 0;
  for (int y = 0; y < bgra.rows; ++y) {
    for (int x = 0; x < bgra.cols; ++x) {
      const cv::Vec4b p = bgra.at<cv::Vec4b>(y, x);
      colour.at<cv::Vec3b>(y, x) = cv::Vec3b(p[0], p[1], p[2]);
      known.at<uchar>(y, x) = p[3] >= 128 ? 1 : 0;
      if (p[3] >= 128) {
        sum += cv::Vec3d(p[0], p[1], p[2]);
        ++opaque;
      }
    }
  }
  for (int pass = 0; pass < kFillPasses; ++pass) {
    const cv::Mat before = known.clone();
    const cv::Mat colour_before = colour.clone();
    bool changed = false;
    for (int y = 0; y < bgra.rows; ++y) {
      for (int x = 0; x < bgra.cols; ++x) {
        if (before.at<uchar>(y, x)) continue;
        cv::Vec3i acc(0, 0, 0);
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int yy = y + dy, xx = x + dx;
            if (yy < 0 || xx < 0 || yy >= bgra.rows || xx >= bgra.cols || !before.at<uchar>(yy, xx)) continue;
            const cv::Vec3b c = colour_before.at<cv::Vec3b>(yy, xx);
            acc += cv::Vec3i(c[0], c[1], c[2]);
            ++n;
          }
        }
        if (n == 0) continue;
        colour.at<cv::Vec3b>(y, x) =
            cv::Vec3b(static_cast<uchar>((acc[0] + n / 2) / n), static_cast<uchar>((acc[1] + n / 2) / n),
                      static_cast<uchar>((acc[2] + n / 2) / n));
        known.at<uchar>(y, x) = 1;
        changed = true;
      }
    }
    if (!changed) break;
  }
  const cv::Vec3b mean =
      opaque > 0 ? cv::Vec3b(static_cast<uchar>(sum[0] / opaque), static_cast<uchar>(sum[1] / opaque),
                             static_cast<uchar>(sum[2] / opaque))
                 : cv::Vec3b(128, 128, 128);
  for (int y = 0; y < bgra.rows; ++y) {
    for (int x = 0; x < bgra.cols; ++x) {
      if (!known.at<uchar>(y, x)) colour.at<cv::Vec3b>(y, x) = mean;
    }
  }
  return colour;
}

}  // namespace

bool Sprite::opaque(double s, double t) const {
  const double x = std::clamp(s, 0.0, alpha.cols - 1.0);
  const double y = std::clamp(t, 0.0, alpha.rows - 1.0);
  const int x0 = std::min(static_cast<int>(x), std::max(0, alpha.cols - 2));
  const int y0 = std::min(static_cast<int>(y), std::max(0, alpha.rows - 2));
  const int x1 = std::min(x0 + 1, alpha.cols - 1);
  const int y1 = std::min(y0 + 1, alpha.rows - 1);
  const double fx = x - x0;
  const double fy = y - y0;
  const uchar* r0 = alpha.ptr<uchar>(y0);
  const uchar* r1 = alpha.ptr<uchar>(y1);
  const double top = r0[x0] + fx * (r0[x1] - r0[x0]);
  const double bottom = r1[x0] + fx * (r1[x1] - r1[x0]);
  return top + fy * (bottom - top) >= 127.5;
}

fs::path default_sprite_dir() { return util::source_dir() / "people_sprites"; }

fs::path default_mot_dir() { return util::shared_dir() / "data" / "mot"; }

bool has_sprites(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / "sprites.json", ec);
}

SpriteChoice resolve_sprite_dir(const std::string& option) {
  const std::string how =
      "build them with scripts/build_people_sprites.sh or `crowdslam synth-sprites --out DIR`";
  if (option == "none") return {"", "synth: the people are textured boxes (--sprites none)"};
  if (option.empty()) {
    const fs::path dir = default_sprite_dir();
    if (has_sprites(dir)) return {dir.string(), ""};
    return {"",
            "synth: the people are textured boxes: no person sprites in " + dir.string() + " (" + how + ")"};
  }
  if (!has_sprites(option))
    throw input_error((fs::path(option) / "sprites.json").string(), "no person sprites (" + how + ")");
  return {option, ""};
}

std::vector<Sprite> load_sprites(const fs::path& dir) {
  const fs::path list = dir / "sprites.json";
  const std::string list_name = list.string();
  std::ifstream in(list);
  if (!in) throw input_error(list_name, "cannot open file");
  std::ostringstream text;
  text << in.rdbuf();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::exception& e) {
    throw input_error(list_name, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object() || !j.contains("sprites") || !j["sprites"].is_array()) {
    throw input_error(list_name, "expected an object with a \"sprites\" array");
  }
  std::vector<Sprite> sprites;
  for (const auto& entry : j["sprites"]) {
    Sprite sprite;
    try {
      sprite.record.file = entry.at("file").get<std::string>();
      sprite.record.sequence = entry.value("sequence", std::string());
      sprite.record.frame = entry.value("frame", 0);
      sprite.record.id = entry.value("id", 0);
      sprite.record.width = entry.at("width").get<int>();
      sprite.record.height = entry.at("height").get<int>();
      sprite.record.fill = entry.value("fill", 0.0);
      sprite.record.facing = entry.value("facing", 0);
    } catch (const nlohmann::json::exception& e) {
      throw input_error(list_name, std::string("sprite entry: ") + e.what());
    }
    if (sprite.record.file.empty() || sprite.record.file.find('/') != std::string::npos) {
      throw input_error(list_name, "sprite entry: bad file name '" + clip_text(sprite.record.file) + "'");
    }
    const fs::path path = dir / sprite.record.file;
    const cv::Mat bgra = io::opencv_extras().imread(path.string(), cv::IMREAD_UNCHANGED);
    if (bgra.empty()) throw input_error(path.string(), "cannot read sprite");
    if (bgra.type() != CV_8UC4)
      throw input_error(path.string(), "sprite must be a 4-channel (BGRA) 8-bit PNG");
    if (bgra.cols != sprite.record.width || bgra.rows != sprite.record.height) {
      throw input_error(path.string(), "sprite is " + std::to_string(bgra.cols) + "x" +
                                           std::to_string(bgra.rows) + ", sprites.json says " +
                                           std::to_string(sprite.record.width) + "x" +
                                           std::to_string(sprite.record.height));
    }
    if (bgra.cols < 4 || bgra.rows < 8) throw input_error(path.string(), "sprite is too small");
    cv::extractChannel(bgra, sprite.alpha, 3);
    cv::threshold(sprite.alpha, sprite.alpha, 127, 255, cv::THRESH_BINARY);
    if (cv::countNonZero(sprite.alpha) == 0) throw input_error(path.string(), "sprite has no opaque pixel");
    sprite.colour = Texture(fill_transparent(bgra));
    sprites.push_back(std::move(sprite));
  }
  if (sprites.empty()) throw input_error(list_name, "lists no sprites");
  return sprites;
}

}  // namespace crowdslam::synth
