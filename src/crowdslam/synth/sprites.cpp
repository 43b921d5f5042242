// Person sprites cut out of MOT sequences with grabCut (sprites.h). Loading them: sprite_load.cpp.
#include "crowdslam/synth/sprites.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/io/opencv_extras.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::synth {
namespace fs = std::filesystem;
// Named, not anonymous: the library is built in unity batches, where anonymous namespaces of
// several files are one.
namespace sprite_cuts {

constexpr std::uint64_t kGrabCutSeed = 0x5b17e5;
constexpr int kMinFramesApart = 10;     // sprites of one person come from frames at least this far apart
constexpr int kAttemptsPerSprite = 8;   // grabCut runs per wanted sprite of a person, at most
constexpr double kHeadFeetBand = 0.12;  // the foreground must reach into the top and bottom 12 % of the box
constexpr double kMinWidthFraction = 0.4;
constexpr double kMinLargestPart = 0.85;  // the largest connected part holds this much of the foreground

struct GtRow {
  int frame = 0;
  int id = 0;
  cv::Rect2d box;
  bool counts = true;  // flag != 0 (and, for 9-column files, class 1)
};

std::vector<GtRow> read_gt(const fs::path& path) {
  const std::string file = path.string();
  std::vector<GtRow> rows;
  const std::vector<std::string> lines = read_lines(file);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string t = trim(lines[i]);
    if (t.empty() || t[0] == '#') continue;
    const int line = static_cast<int>(i + 1);
    const std::vector<std::string> f = split_fields(t);
    if (f.size() < 6)
      throw input_error(file, line, "expected at least 6 fields (frame,id,left,top,width,height)");
    double v[8] = {0, 0, 0, 0, 0, 0, 1, 1};
    for (size_t k = 0; k < std::min<size_t>(f.size(), 8); ++k) {
      const auto value = parse_double(f[k]);
      if (!value || !std::isfinite(*value)) {
        throw input_error(file, line,
                          "field " + std::to_string(k + 1) + " is not a number: '" + clip_text(f[k]) + "'");
      }
      v[k] = *value;
    }
    if (v[0] < 1 || v[0] != std::floor(v[0])) throw input_error(file, line, "frame must be an integer >= 1");
    GtRow row;
    row.frame = static_cast<int>(v[0]);
    row.id = static_cast<int>(v[1]);
    row.box = cv::Rect2d(v[2], v[3], v[4], v[5]);
    row.counts = v[6] != 0 && (f.size() != 9 || v[7] == 1);
    if (row.box.width > 0 && row.box.height > 0) rows.push_back(row);
  }
  return rows;
}

fs::path frame_image(const fs::path& sequence, int frame) {
  char name[32];
  for (const char* ext : {".jpg", ".png", ".jpeg"}) {
    std::snprintf(name, sizeof name, "%06d%s", frame, ext);
    const fs::path p = sequence / "img1" / name;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p;
  }
  std::snprintf(name, sizeof name, "%06d.jpg", frame);
  return sequence / "img1" / name;
}

cv::Mat read_image(const fs::path& path) {
  cv::Mat image = io::opencv_extras().imread(path.string(), cv::IMREAD_COLOR);
  if (image.empty()) throw input_error(path.string(), "cannot read image");
  return image;
}

// Fraction of `box` covered by the most overlapping other box of the frame.
double overlap_by_others(const GtRow& row, const std::vector<const GtRow*>& frame_rows) {
  double worst = 0.0;
  for (const GtRow* other : frame_rows) {
    if (other == &row) continue;
    worst = std::max(worst, (row.box & other->box).area() / row.box.area());
  }
  return worst;
}

// +1 / -1 when the person's box centre moves right / left by a tenth of its width within +-5 frames.
int facing_of(const GtRow& row, const std::map<int, const GtRow*>& track) {
  const GtRow* first = &row;
  const GtRow* last = &row;
  for (const auto& [frame, r] : track) {
    if (frame >= row.frame - 5 && frame < first->frame) first = r;
    if (frame <= row.frame + 5 && frame > last->frame) last = r;
  }
  const double dx = (last->box.x + last->box.width / 2) - (first->box.x + first->box.width / 2);
  if (std::abs(dx) < 0.1 * row.box.width) return 0;
  return dx > 0 ? 1 : -1;
}

// Indices 0..n-1 in an order that spreads over the range: the middle, the quarters, the eighths, ...
std::vector<int> spread_order(int n) {
  std::vector<int> order;
  std::vector<char> used(n, 0);
  for (int denominator = 2; static_cast<int>(order.size()) < n && denominator <= 2 * n + 2;
       denominator *= 2) {
    for (int k = 1; k < denominator; k += 2) {
      const int i = static_cast<int>(std::lround(static_cast<double>(k) / denominator * (n - 1)));
      if (!used[i]) {
        used[i] = 1;
        order.push_back(i);
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!used[i]) order.push_back(i);
  }
  return order;
}

struct Person {
  std::string sequence;
  fs::path folder;
  int id = 0;
  std::vector<const GtRow*> candidates;  // by frame
  std::map<int, const GtRow*> track;     // every row of the id, by frame
  std::vector<int> order;                // candidate indices to try, spread over the track
  size_t next = 0;
  int attempts = 0;
  std::vector<int> taken_frames;
};

void write_png(const fs::path& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = io::opencv_extras().imwrite(path.string(), image, {cv::IMWRITE_PNG_COMPRESSION, 6});
  } catch (const cv::Exception& e) {
    throw input_error(path.string(), std::string("cannot write image: ") + e.what());
  }
  if (!ok) throw input_error(path.string(), "cannot write image");
}

}  // namespace sprite_cuts

void SpriteExtractOptions::check() const {
  const auto fail = [](const std::string& key, const std::string& what) {
    throw InputError(key + ": " + what);
  };
  if (min_height_px < 16 || min_height_px > 10000)
    fail("--min-height", "must be between 16 and 10000 pixels, got " + std::to_string(min_height_px));
  if (!(max_overlap >= 0.0 && max_overlap <= 1.0))
    fail("--max-overlap", "must be in [0, 1], got " + std::to_string(max_overlap));
  if (border_px < 0) fail("border", "must be >= 0");
  if (iterations < 1 || iterations > 20)
    fail("--iterations", "must be between 1 and 20, got " + std::to_string(iterations));
  if (per_id < 1 || per_id > 100)
    fail("--per-id", "must be between 1 and 100, got " + std::to_string(per_id));
  if (max_sprites < 1 || max_sprites > 100000)
    fail("--max-sprites", "must be between 1 and 100000, got " + std::to_string(max_sprites));
  if (!(min_fill > 0.0 && min_fill < max_fill && max_fill <= 1.0))
    fail("fill", "need 0 < min_fill < max_fill <= 1");
}

std::optional<cv::Mat> cut_out_person(const cv::Mat& image, const cv::Rect& box,
                                      const SpriteExtractOptions& options, double* fill) {
  using namespace sprite_cuts;
  CV_Assert(image.type() == CV_8UC3);
  const cv::Rect whole(0, 0, image.cols, image.rows);
  if ((box & whole) != box || box.width < 8 || box.height < 8) return std::nullopt;
  // grabCut on a crop around the box: the box plus a quarter of its width at the sides and a little above
  // and below, so the background model sees the person's surroundings.
  const int mx = box.width / 4;
  const int my = box.height / 12;
  const cv::Rect roi = cv::Rect(box.x - mx, box.y - my, box.width + 2 * mx, box.height + 2 * my) & whole;
  const cv::Rect inner(box.x - roi.x, box.y - roi.y, box.width, box.height);
  cv::Mat mask(roi.size(), CV_8U, cv::Scalar(cv::GC_BGD));
  cv::Mat bgd_model, fgd_model;
  cv::setRNGSeed(static_cast<int>(kGrabCutSeed));  // grabCut's k-means initialisation draws from it
  cv::grabCut(image(roi), mask, inner, bgd_model, fgd_model, options.iterations, cv::GC_INIT_WITH_RECT);
  cv::Mat foreground = (mask(inner) & 1);  // GC_FGD (1) and GC_PR_FGD (3)
  foreground *= 255;
  cv::morphologyEx(foreground, foreground, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
  const int total = cv::countNonZero(foreground);
  if (total == 0) return std::nullopt;
  cv::Mat labels, stats, centroids;
  const int parts = cv::connectedComponentsWithStats(foreground, labels, stats, centroids, 8, CV_32S);
  int best = 0;
  for (int i = 1; i < parts; ++i) {
    if (best == 0 || stats.at<int>(i, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA)) best = i;
  }
  const int area = stats.at<int>(best, cv::CC_STAT_AREA);
  const cv::Rect part(stats.at<int>(best, cv::CC_STAT_LEFT), stats.at<int>(best, cv::CC_STAT_TOP),
                      stats.at<int>(best, cv::CC_STAT_WIDTH), stats.at<int>(best, cv::CC_STAT_HEIGHT));
  const double box_area = static_cast<double>(box.area());
  const double part_fill = area / box_area;
  if (fill) *fill = part_fill;
  const bool plausible = area >= kMinLargestPart * total && part_fill >= options.min_fill &&
                         part_fill <= options.max_fill && part.y <= kHeadFeetBand * box.height &&
                         part.y + part.height >= (1.0 - kHeadFeetBand) * box.height &&
                         part.width >= kMinWidthFraction * box.width;
  if (!plausible) {
    spdlog::debug(
        "synth-sprites: box {}x{} at ({}, {}) rejected: largest part {:.2f} of the foreground, fill {:.2f}, "
        "rows {}-{}, width {}",
        box.width, box.height, box.x, box.y, static_cast<double>(area) / total, part_fill, part.y,
        part.y + part.height, part.width);
    return std::nullopt;
  }
  cv::Mat sprite(part.size(), CV_8UC4, cv::Scalar::all(0));
  const cv::Mat source = image(box);
  for (int y = 0; y < part.height; ++y) {
    const int* label_row = labels.ptr<int>(part.y + y);
    const auto* in = source.ptr<cv::Vec3b>(part.y + y);
    auto* out = sprite.ptr<cv::Vec4b>(y);
    for (int x = 0; x < part.width; ++x) {
      if (label_row[part.x + x] != best) continue;
      const cv::Vec3b c = in[part.x + x];
      out[x] = cv::Vec4b(c[0], c[1], c[2], 255);
    }
  }
  return sprite;
}

std::vector<fs::path> find_mot_sequences(const fs::path& path) {
  const auto is_sequence = [](const fs::path& p) {
    std::error_code ec;
    return fs::is_directory(p / "img1", ec) && fs::is_regular_file(p / "gt" / "gt.txt", ec);
  };
  if (is_sequence(path)) return {path};
  std::vector<fs::path> out;
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return out;
  for (const auto& entry : fs::directory_iterator(path, ec)) {
    if (is_sequence(entry.path())) out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

SpriteSet extract_sprites(const std::vector<fs::path>& sequences, const fs::path& out_dir_arg,
                          const SpriteExtractOptions& options, bool force, const SequenceDone& on_sequence) {
  using namespace sprite_cuts;
  options.check();
  if (sequences.empty()) throw InputError("--mot: no MOT sequences (folders with img1/ and gt/gt.txt)");
  fs::path out_dir = out_dir_arg;
  if (!out_dir.has_filename()) out_dir = out_dir.parent_path();
  if (out_dir.empty()) throw InputError("--out: empty output directory");
  std::error_code ec;
  if (fs::exists(out_dir, ec)) {
    if (!fs::is_directory(out_dir, ec)) throw input_error(out_dir.string(), "exists and is not a directory");
    if (!fs::is_empty(out_dir, ec) && !force) {
      throw input_error(out_dir.string(),
                        "output directory exists and is not empty (use --force to replace it)");
    }
  }
  // Every sequence's rows and the people worth trying, before any grabCut.
  std::vector<std::vector<GtRow>> rows(sequences.size());
  std::vector<Person> people;
  SpriteSet set;
  for (size_t s = 0; s < sequences.size(); ++s) {
    const fs::path& folder = sequences[s];
    const std::string name = folder.filename().string();
    rows[s] = read_gt(folder / "gt" / "gt.txt");
    SequenceSprites figures;
    figures.name = name;
    figures.boxes = static_cast<int>(rows[s].size());
    if (rows[s].empty()) {
      set.sequences.push_back(figures);
      continue;
    }
    const cv::Mat first = read_image(frame_image(folder, rows[s].front().frame));
    std::map<int, std::vector<const GtRow*>> by_frame;
    std::map<int, std::map<int, const GtRow*>> by_id;
    for (const GtRow& r : rows[s]) {
      by_frame[r.frame].push_back(&r);
      by_id[r.id][r.frame] = &r;
    }
    const double b = options.border_px;
    std::map<int, Person> candidates_of;
    for (const GtRow& r : rows[s]) {
      if (!r.counts || r.box.height < options.min_height_px) continue;
      if (r.box.x < b || r.box.y < b || r.box.x + r.box.width > first.cols - b ||
          r.box.y + r.box.height > first.rows - b) {
        continue;
      }
      if (overlap_by_others(r, by_frame[r.frame]) > options.max_overlap) continue;
      Person& p = candidates_of[r.id];
      p.candidates.push_back(&r);
      ++figures.candidates;
    }
    for (auto& [id, p] : candidates_of) {
      p.sequence = name;
      p.folder = folder;
      p.id = id;
      std::sort(p.candidates.begin(), p.candidates.end(),
                [](const GtRow* a, const GtRow* c) { return a->frame < c->frame; });
      p.track = by_id[id];
      p.order = spread_order(static_cast<int>(p.candidates.size()));
      people.push_back(std::move(p));
    }
    set.sequences.push_back(figures);
  }

  fs::path tmp = out_dir;
  tmp += ".tmp-" + std::to_string(::getpid());
  remove_quietly(tmp);
  remove_stale_temporary_dirs(out_dir);  // of a run killed with SIGKILL
  try {
    fs::create_directories(tmp, ec);
    if (ec) throw input_error(tmp.string(), "cannot create directory: " + ec.message());
    // Round robin over the people: one sprite each per pass, so the cap keeps every identity.
    std::map<std::string, SequenceSprites*> figures_of;
    for (auto& f : set.sequences) figures_of[f.name] = &f;
    for (int pass = 0; pass < options.per_id && static_cast<int>(set.sprites.size()) < options.max_sprites;
         ++pass) {
      for (Person& p : people) {
        if (static_cast<int>(set.sprites.size()) >= options.max_sprites) break;
        while (p.next < p.order.size() && p.attempts < kAttemptsPerSprite * options.per_id) {
          const GtRow& r = *p.candidates[p.order[p.next++]];
          const bool near_taken = std::any_of(p.taken_frames.begin(), p.taken_frames.end(),
                                              [&](int f) { return std::abs(f - r.frame) < kMinFramesApart; });
          if (near_taken) continue;
          ++p.attempts;
          const cv::Mat image = read_image(frame_image(p.folder, r.frame));
          const cv::Rect box(static_cast<int>(std::lround(r.box.x)), static_cast<int>(std::lround(r.box.y)),
                             static_cast<int>(std::lround(r.box.width)),
                             static_cast<int>(std::lround(r.box.height)));
          double fill = 0.0;
          const std::optional<cv::Mat> sprite = cut_out_person(image, box, options, &fill);
          if (!sprite) {
            ++figures_of[p.sequence]->rejected;
            continue;
          }
          SpriteRecord record;
          char name[64];
          std::snprintf(name, sizeof name, "_%06d_%03d.png", r.frame, p.id);
          record.file = p.sequence + name;
          record.sequence = p.sequence;
          record.frame = r.frame;
          record.id = p.id;
          record.width = sprite->cols;
          record.height = sprite->rows;
          record.fill = std::round(fill * 1e4) / 1e4;
          record.facing = facing_of(r, p.track);
          write_png(tmp / record.file, *sprite);
          set.sprites.push_back(record);
          ++figures_of[p.sequence]->sprites;
          p.taken_frames.push_back(r.frame);
          break;
        }
      }
    }
    nlohmann::json j;
    j["generator"] = kSpriteGeneratorVersion;
    j["count"] = set.sprites.size();
    j["options"] = {{"min_height_px", options.min_height_px},
                    {"max_overlap", options.max_overlap},
                    {"border_px", options.border_px},
                    {"iterations", options.iterations},
                    {"per_id", options.per_id},
                    {"max_sprites", options.max_sprites},
                    {"min_fill", options.min_fill},
                    {"max_fill", options.max_fill}};
    j["sequences"] = nlohmann::json::array();
    for (const SequenceSprites& f : set.sequences) {
      j["sequences"].push_back({{"name", f.name},
                                {"boxes", f.boxes},
                                {"candidates", f.candidates},
                                {"sprites", f.sprites},
                                {"rejected", f.rejected}});
      if (on_sequence) on_sequence(f);
    }
    j["sprites"] = nlohmann::json::array();
    for (const SpriteRecord& r : set.sprites) {
      j["sprites"].push_back({{"file", r.file},
                              {"sequence", r.sequence},
                              {"frame", r.frame},
                              {"id", r.id},
                              {"width", r.width},
                              {"height", r.height},
                              {"fill", r.fill},
                              {"facing", r.facing}});
    }
    write_file_atomic(tmp / "sprites.json", j.dump(2) + "\n");
    if (fs::exists(out_dir, ec)) fs::remove_all(out_dir);
    fs::rename(tmp, out_dir, ec);
    if (ec) throw input_error(out_dir.string(), "cannot move the sprites into place: " + ec.message());
  } catch (...) {
    remove_quietly(tmp);
    throw;
  }
  return set;
}

}  // namespace crowdslam::synth
