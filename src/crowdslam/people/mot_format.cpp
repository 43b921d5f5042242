#include "crowdslam/people/mot_format.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <algorithm>
#include <sstream>
#include <unordered_map>

#include "crowdslam/io/input_text.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::people {
namespace {

double number(const std::string& path, int line, const std::vector<std::string>& fields, std::size_t i,
              bool finite) {
  const auto value = parse_double(fields[i]);
  if (!value)
    throw input_error(
        path, line, "field " + std::to_string(i + 1) + " is not a number: '" + clip_text(fields[i]) + "'");
  if (finite && !std::isfinite(*value))
    throw input_error(path, line,
                      "field " + std::to_string(i + 1) + " is not finite: '" + clip_text(fields[i]) + "'");
  return *value;
}

bool is_comment_or_blank(const std::string& line) {
  const std::string t = trim(line);
  return t.empty() || t[0] == '#';
}

MotRow parse_row(const std::string& path, int line, const std::vector<std::string>& f, bool mot16_gt) {
  MotRow row;
  row.line = line;
  const double frame = number(path, line, f, 0, true);
  if (frame < 1 || frame != std::floor(frame) || frame > 1e9)
    throw input_error(path, line, "frame must be an integer >= 1, got '" + clip_text(f[0]) + "'");
  row.frame = static_cast<int>(frame);
  const double id = number(path, line, f, 1, true);
  if (id != std::floor(id) || std::abs(id) > 2e9)
    throw input_error(path, line, "id must be an integer, got '" + clip_text(f[1]) + "'");
  row.id = static_cast<int>(id);
  row.box = cv::Rect2f(
      static_cast<float>(number(path, line, f, 2, true)), static_cast<float>(number(path, line, f, 3, true)),
      static_cast<float>(number(path, line, f, 4, true)), static_cast<float>(number(path, line, f, 5, true)));
  if (f.size() > 6) row.score = number(path, line, f, 6, true);
  if (mot16_gt) {
    const double cls = number(path, line, f, 7, true);
    const double vis = number(path, line, f, 8, true);
    if (cls != std::floor(cls) || cls < -1)
      throw input_error(
          path, line,
          "9-column ground truth: class (field 8) must be an integer, got '" + clip_text(f[7]) + "'");
    if (vis < 0 || vis > 1)
      throw input_error(
          path, line,
          "9-column ground truth: visibility (field 9) must be in [0, 1], got '" + clip_text(f[8]) + "'");
    row.object_class = static_cast<int>(cls);
    row.visibility = vis;
  }
  return row;
}

// Keeps the kMaxBoxesPerFrame most confident rows of each frame (rows stay in file order).
void cap_boxes_per_frame(MotFile& file) {
  std::unordered_map<int, std::vector<std::size_t>> rows_of;
  for (std::size_t i = 0; i < file.rows.size(); ++i) rows_of[file.rows[i].frame].push_back(i);
  std::vector<bool> drop(file.rows.size(), false);
  int first_frame = 0;
  for (auto& [frame, rows] : rows_of) {
    if (rows.size() <= kMaxBoxesPerFrame) continue;
    std::stable_sort(rows.begin(), rows.end(),
                     [&](std::size_t a, std::size_t b) { return file.rows[a].score > file.rows[b].score; });
    for (std::size_t k = kMaxBoxesPerFrame; k < rows.size(); ++k) drop[rows[k]] = true;
    ++file.capped_frames;
    file.dropped_over_cap += rows.size() - kMaxBoxesPerFrame;
    if (first_frame == 0 || frame < first_frame) first_frame = frame;
  }
  if (file.capped_frames == 0) return;
  std::vector<MotRow> kept;
  kept.reserve(file.rows.size() - file.dropped_over_cap);
  for (std::size_t i = 0; i < file.rows.size(); ++i)
    if (!drop[i]) kept.push_back(file.rows[i]);
  file.rows = std::move(kept);
  spdlog::warn("{}: {} frame{} with more than {} person boxes (first: frame {}); kept the {} most confident of each, "
               "skipped {} box{}",
               clip_text(file.path), file.capped_frames, file.capped_frames == 1 ? "" : "s", kMaxBoxesPerFrame,
               first_frame, kMaxBoxesPerFrame, file.dropped_over_cap, file.dropped_over_cap == 1 ? "" : "es");
}

}  // namespace

MotFile read_mot_file(const std::string& path, bool ground_truth) {
  MotFile file;
  file.path = path;
  const std::vector<std::string> lines = read_lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i + 1);
    if (is_comment_or_blank(lines[i])) continue;
    const std::vector<std::string> fields = split_fields(lines[i]);
    if (fields.size() < 6)
      throw input_error(
          path, line,
          "expected at least 6 fields (frame,id,x,y,w,h,...), got " + std::to_string(fields.size()));
    if (file.columns == 0) file.columns = fields.size();
    if (fields.size() != file.columns)
      throw input_error(path, line,
                        "expected " + std::to_string(file.columns) + " fields like the first row, got " +
                            std::to_string(fields.size()));
    MotRow row = parse_row(path, line, fields, ground_truth && file.columns == 9);
    const bool empty = !(row.box.width > 0 && row.box.height > 0);
    const bool out_of_range = std::abs(row.box.x) > kMaxBoxCoordinate ||
                              std::abs(row.box.y) > kMaxBoxCoordinate || row.box.width > kMaxBoxCoordinate ||
                              row.box.height > kMaxBoxCoordinate;
    if (empty || out_of_range) {
      ++(empty ? file.dropped_empty : file.dropped_out_of_range);
      if (file.first_dropped_line == 0) file.first_dropped_line = line;
      continue;
    }
    file.rows.push_back(row);
  }
  cap_boxes_per_frame(file);
  if (file.first_dropped_line > 0)
    spdlog::warn(
        "{}:{}: {} box{} skipped: {} with zero or negative width/height, {} with a coordinate or size beyond "
        "1e6 pixels",
        clip_text(path), file.first_dropped_line, file.dropped_empty + file.dropped_out_of_range,
        file.dropped_empty + file.dropped_out_of_range == 1 ? "" : "es", file.dropped_empty,
        file.dropped_out_of_range);
  return file;
}

void write_mot_detections(const std::string& path, const std::vector<FrameBoxes>& frames) {
  AtomicFile out(path);
  std::ostream& s = out.stream();
  s.precision(6);
  for (const FrameBoxes& f : frames)
    for (const PersonBox& b : f.boxes)
      s << (f.frame_index + 1) << ",-1," << b.box.x << ',' << b.box.y << ',' << b.box.width << ','
        << b.box.height << ',' << b.confidence << ",-1,-1,-1\n";
  out.commit();
}

}  // namespace crowdslam::people
