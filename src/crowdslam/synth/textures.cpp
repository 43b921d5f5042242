#include "crowdslam/synth/textures.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/io/opencv_extras.h"

namespace crowdslam::synth {
namespace {

constexpr int kMaxLevels = 6;

cv::Scalar random_colour(Rng& rng, double lo, double hi) {
  return cv::Scalar(rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi));
}

// Smooth noise in [0, 1] with the given cell size in texels (one octave).
cv::Mat value_noise(int width, int height, double cell, Rng& rng) {
  const int gw = static_cast<int>(std::ceil(width / cell)) + 2;
  const int gh = static_cast<int>(std::ceil(height / cell)) + 2;
  cv::Mat grid(gh, gw, CV_32F);
  for (int y = 0; y < gh; ++y) {
    for (int x = 0; x < gw; ++x) grid.at<float>(y, x) = static_cast<float>(rng.uniform());
  }
  cv::Mat big;
  cv::resize(grid, big, cv::Size(static_cast<int>(gw * cell), static_cast<int>(gh * cell)), 0, 0,
             cv::INTER_CUBIC);
  return big(cv::Rect(0, 0, width, height)).clone();
}

// Multi-octave noise in roughly [0, 1].
cv::Mat fractal_noise(int width, int height, double base_cell, Rng& rng) {
  cv::Mat sum = cv::Mat::zeros(height, width, CV_32F);
  double amplitude = 1.0;
  double total = 0.0;
  for (double cell = base_cell; cell >= 2.0; cell /= 2.0) {
    sum += amplitude * value_noise(width, height, cell, rng);
    total += amplitude;
    amplitude *= 0.6;
  }
  return sum / total;
}

// Blends two colours by a [0, 1] mask into an 8-bit BGR image.
cv::Mat blend(const cv::Mat& mask, const cv::Scalar& a, const cv::Scalar& b) {
  cv::Mat out(mask.size(), CV_8UC3);
  for (int y = 0; y < mask.rows; ++y) {
    const float* m = mask.ptr<float>(y);
    auto* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < mask.cols; ++x) {
      const double w = std::clamp(static_cast<double>(m[x]) * 1.6 - 0.3, 0.0, 1.0);
      for (int c = 0; c < 3; ++c) o[x][c] = cv::saturate_cast<uchar>(a[c] * (1.0 - w) + b[c] * w);
    }
  }
  return out;
}

void draw_shapes(cv::Mat& image, Rng& rng, int count) {
  const int w = image.cols;
  const int h = image.rows;
  for (int i = 0; i < count; ++i) {
    const cv::Scalar colour = random_colour(rng, 0, 255);
    const cv::Point p(rng.below(w), rng.below(h));
    const int size = 4 + rng.below(std::max(5, std::min(w, h) / 6));
    switch (rng.below(3)) {
      case 0:
        cv::rectangle(image, p, p + cv::Point(size, size * (1 + rng.below(3)) / 2), colour, cv::FILLED);
        break;
      case 1: cv::circle(image, p, size / 2 + 1, colour, cv::FILLED, cv::LINE_AA); break;
      default:
        cv::line(image, p, cv::Point(rng.below(w), rng.below(h)), colour, 1 + rng.below(4), cv::LINE_AA);
    }
  }
}

// A random crop of a random photo, resized to (width, height), mildly tinted and maybe mirrored.
cv::Mat photo_tile(int width, int height, Rng& rng, const std::vector<cv::Mat>& photos) {
  const cv::Mat& photo = photos[rng.below(static_cast<int>(photos.size()))];
  const double aspect = static_cast<double>(width) / height;
  // Largest crop of the wanted aspect that fits, then shrunk by a random factor.
  double cw = photo.cols;
  double ch = cw / aspect;
  if (ch > photo.rows) {
    ch = photo.rows;
    cw = ch * aspect;
  }
  const double shrink = rng.uniform(0.55, 1.0);
  cw *= shrink;
  ch *= shrink;
  const int x0 = static_cast<int>(rng.uniform(0.0, photo.cols - cw));
  const int y0 = static_cast<int>(rng.uniform(0.0, photo.rows - ch));
  const cv::Rect roi(x0, y0, std::max(1, static_cast<int>(cw)), std::max(1, static_cast<int>(ch)));
  cv::Mat tile;
  cv::resize(photo(roi & cv::Rect(0, 0, photo.cols, photo.rows)), tile, cv::Size(width, height), 0, 0,
             cv::INTER_AREA);
  if (rng.below(2) == 1) cv::flip(tile, tile, 1);
  const cv::Scalar tint(rng.uniform(0.85, 1.15), rng.uniform(0.85, 1.15), rng.uniform(0.85, 1.15));
  cv::multiply(tile, tint, tile);
  return tile;
}

}  // namespace

Texture::Texture(const cv::Mat& image) {
  CV_Assert(image.type() == CV_8UC3 && !image.empty());
  levels_.push_back(image.clone());
  while (static_cast<int>(levels_.size()) < kMaxLevels && levels_.back().cols >= 8 &&
         levels_.back().rows >= 8) {
    cv::Mat next;
    cv::pyrDown(levels_.back(), next);
    levels_.push_back(next);
  }
}

cv::Vec3f Texture::bilinear(int level, double s, double t) const {
  const cv::Mat& img = levels_[level];
  const double scale = 1.0 / (1 << level);
  const double x = std::clamp(s * scale, 0.0, img.cols - 1.0);
  const double y = std::clamp(t * scale, 0.0, img.rows - 1.0);
  const int x0 = std::min(static_cast<int>(x), img.cols - 2 < 0 ? 0 : img.cols - 2);
  const int y0 = std::min(static_cast<int>(y), img.rows - 2 < 0 ? 0 : img.rows - 2);
  const int x1 = std::min(x0 + 1, img.cols - 1);
  const int y1 = std::min(y0 + 1, img.rows - 1);
  const float fx = static_cast<float>(x - x0);
  const float fy = static_cast<float>(y - y0);
  const auto* r0 = img.ptr<cv::Vec3b>(y0);
  const auto* r1 = img.ptr<cv::Vec3b>(y1);
  cv::Vec3f out;
  for (int c = 0; c < 3; ++c) {
    const float top = r0[x0][c] + fx * (r0[x1][c] - r0[x0][c]);
    const float bottom = r1[x0][c] + fx * (r1[x1][c] - r1[x0][c]);
    out[c] = top + fy * (bottom - top);
  }
  return out;
}

cv::Vec3f Texture::sample(double s, double t, double lod) const {
  if (lod <= 0.0) return bilinear(0, s, t);
  const int last = static_cast<int>(levels_.size()) - 1;
  if (lod >= last) return bilinear(last, s, t);
  const int level = static_cast<int>(lod);
  const float w = static_cast<float>(lod - level);
  return bilinear(level, s, t) * (1.0f - w) + bilinear(level + 1, s, t) * w;
}

std::vector<cv::Mat> load_photos(const std::string& dir) {
  static const char* const kNames[] = {
      "building.jpg", "fruits.jpg",     "baboon.jpg",      "graf1.png",       "home.jpg",
      "starry_night.jpg", "aero1.jpg",  "board.jpg",       "leuvenA.jpg",     "stuff.jpg",
      "butterfly.jpg", "messi5.jpg",    "apple.jpg",       "orange.jpg",      "rubberwhale1.png",
      "smarties.png",  "graf3.png",     "aloeL.jpg",       "HappyFish.jpg",   "lena.jpg",
      "box_in_scene.png", "blox.jpg",   "squirrel_cls.jpg", "ela_original.jpg", "pic1.png"};
  std::vector<cv::Mat> photos;
  if (dir.empty()) return photos;
  for (const char* name : kNames) {
    const std::filesystem::path path = std::filesystem::path(dir) / name;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) continue;
    cv::Mat image = io::opencv_extras().imread(path.string(), cv::IMREAD_COLOR);
    if (image.empty() || image.cols < 64 || image.rows < 64) continue;
    photos.push_back(image);
  }
  return photos;
}

cv::Mat make_procedural_tile(int width, int height, Rng& rng) {
  // Posterised noise (crisp blob borders) in two colours, fine grain, then shapes and letters for corners.
  cv::Mat noise = fractal_noise(width, height, rng.uniform(24.0, 96.0), rng);
  for (int y = 0; y < noise.rows; ++y) {
    auto* row = noise.ptr<float>(y);
    for (int x = 0; x < noise.cols; ++x) row[x] = std::floor(row[x] * 5.0f) / 4.0f;
  }
  cv::Mat tile = blend(noise, random_colour(rng, 20, 235), random_colour(rng, 20, 235));
  cv::Mat grain(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    auto* row = grain.ptr<cv::Vec3b>(y);
    for (int x = 0; x < width; ++x) row[x] = cv::Vec3b::all(static_cast<uchar>(rng.below(24)));
  }
  tile += grain;
  draw_shapes(tile, rng, 10 + (width * height) / 2500);
  const int lines = 1 + height / 60;
  for (int i = 0; i < lines; ++i) {
    std::string text;
    for (int c = 0, n = 3 + rng.below(8); c < n; ++c) text += static_cast<char>('A' + rng.below(26));
    cv::putText(tile, text, cv::Point(rng.below(std::max(1, width)), rng.below(std::max(1, height))),
                cv::FONT_HERSHEY_SIMPLEX, rng.uniform(0.6, 1.6), random_colour(rng, 0, 255), 2, cv::LINE_AA);
  }
  return tile;
}

cv::Mat make_collage(int width, int height, Rng& rng, const std::vector<cv::Mat>& photos) {
  cv::Mat canvas(height, width, CV_8UC3, cv::Scalar::all(128));
  const cv::Rect whole(0, 0, width, height);
  int y = 0;
  while (y < height) {
    const int row_h = std::max(16, static_cast<int>(rng.uniform(0.7, 1.4) * kTexelsPerMetre));
    int x = -static_cast<int>(rng.uniform(0.0, 0.5) * kTexelsPerMetre);  // stagger rows like bricks
    while (x < width) {
      const int tile_w = std::max(16, static_cast<int>(rng.uniform(0.8, 1.6) * row_h));
      const cv::Rect dst = cv::Rect(x, y, tile_w, row_h) & whole;
      if (dst.area() > 0) {
        const cv::Mat tile = photos.empty() ? make_procedural_tile(tile_w, row_h, rng)
                                            : photo_tile(tile_w, row_h, rng, photos);
        tile(cv::Rect(dst.x - x, dst.y - y, dst.width, dst.height)).copyTo(canvas(dst));
      }
      x += tile_w;
    }
    y += row_h;
  }
  return canvas;
}

cv::Mat make_clothing(int width, int height, Rng& rng) {
  cv::Mat image(height, width, CV_8UC3);
  const int head_end = height * 25 / 175;
  const int shirt_end = height * 85 / 175;
  // Head: skin with darker hair on top and a bit of noise.
  const double skin = rng.uniform(0.35, 1.0);
  const cv::Scalar skin_colour(90 + 80 * skin, 120 + 80 * skin, 150 + 90 * skin);
  const cv::Scalar hair_colour = random_colour(rng, 10, 70);
  cv::Mat head_noise = fractal_noise(width, head_end, 12.0, rng);
  blend(head_noise, skin_colour, skin_colour * 0.75).copyTo(image(cv::Rect(0, 0, width, head_end)));
  image(cv::Rect(0, 0, width, head_end / 3)) = hair_colour;
  // Shirt: stripes of two saturated colours modulated by noise, plus a few shapes (print, buttons).
  const cv::Scalar a = random_colour(rng, 0, 255);
  const cv::Scalar b = random_colour(rng, 0, 255);
  const int shirt_h = shirt_end - head_end;
  const cv::Mat noise = fractal_noise(width, shirt_h, 16.0, rng);
  const double period = rng.uniform(10.0, 28.0);
  const bool vertical = rng.below(2) == 1;
  cv::Mat mask(shirt_h, width, CV_32F);
  for (int y = 0; y < shirt_h; ++y) {
    for (int x = 0; x < width; ++x) {
      const double phase = std::fmod((vertical ? x : y) / period, 1.0);
      mask.at<float>(y, x) = static_cast<float>((phase < 0.5 ? 0.85 : 0.15) + 0.3 * (noise.at<float>(y, x) - 0.5));
    }
  }
  cv::Mat shirt = blend(mask, a, b);
  draw_shapes(shirt, rng, 8);
  shirt.copyTo(image(cv::Rect(0, head_end, width, shirt_h)));
  // Trousers: a dark colour with noise.
  const cv::Scalar dark = random_colour(rng, 20, 110);
  const int legs_h = height - shirt_end;
  blend(fractal_noise(width, legs_h, 10.0, rng), dark, dark * 0.6)
      .copyTo(image(cv::Rect(0, shirt_end, width, legs_h)));
  return image;
}

}  // namespace crowdslam::synth
