#include "crowdslam/io/trajectory.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <string_view>

#include <spdlog/spdlog.h>

#include "crowdslam/io/dataset_list.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::io {
namespace {

using geometry::Mat3;
using geometry::SE3;
using geometry::Vec3;

constexpr double kEurocStampThreshold = 1e11;  // a stamp this large is nanoseconds, not seconds

bool is_comment_or_blank(const std::string& line) {
  const std::string trimmed = trim(line);
  return trimmed.empty() || trimmed.front() == '#';
}

// One data line of a trajectory file: its 1-based line number and its fields.
struct DataLine {
  int line_number = 0;
  std::vector<std::string> fields;
};

std::vector<DataLine> read_data_lines(const std::string& path) {
  const std::vector<std::string> lines = read_lines(path);
  std::vector<DataLine> data;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (is_comment_or_blank(lines[i])) continue;
    data.push_back({static_cast<int>(i + 1), split_fields(lines[i], true)});
  }
  return data;
}

void require_fields(const std::string& path, const DataLine& line, std::size_t count, const char* layout) {
  if (line.fields.size() < count) {
    throw input_error(path, line.line_number,
                      "too few fields: expected " + std::to_string(count) + " (" + layout + "), got " +
                          std::to_string(line.fields.size()));
  }
}

double number(const std::string& path, const DataLine& line, std::size_t index) {
  const std::string& text = line.fields[index];
  const std::optional<double> value = parse_double(text);
  if (!value) {
    throw input_error(path, line.line_number,
                      "non-numeric value '" + text + "' in field " + std::to_string(index + 1));
  }
  if (!std::isfinite(*value)) {
    throw input_error(path, line.line_number,
                      "non-finite value '" + text + "' in field " + std::to_string(index + 1));
  }
  return *value;
}

Eigen::Quaterniond quaternion(const std::string& path, const DataLine& line, double w, double x, double y,
                              double z) {
  const Eigen::Quaterniond q(w, x, y, z);
  if (!(q.norm() > 1e-12)) throw input_error(path, line.line_number, "zero quaternion");
  return q.normalized();
}

// EuRoC stamps are integer nanoseconds, sometimes written with a ".000" fraction. Splitting seconds
// from nanoseconds keeps all the precision a double in seconds can hold.
double euroc_stamp_s(const std::string& path, const DataLine& line) {
  const std::string& text = line.fields[0];
  const std::size_t dot = text.find('.');
  const std::optional<long long> whole = parse_int(text.substr(0, dot));
  std::optional<double> fraction = 0.0;
  if (dot != std::string::npos) fraction = parse_double("0" + text.substr(dot));
  if (whole && fraction && dot != 0) {
    const long long seconds = *whole / 1000000000LL;
    const long long nanoseconds = *whole % 1000000000LL;
    const double sign = text.front() == '-' ? -1.0 : 1.0;
    return static_cast<double>(seconds) + (static_cast<double>(nanoseconds) + sign * *fraction) * 1e-9;
  }
  return number(path, line, 0) * 1e-9;  // scientific notation etc.; also reports malformed stamps
}

void check_rotation(const std::string& path, const DataLine& line, const Mat3& rotation) {
  const double orthogonality = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality > 1e-2 || rotation.determinant() <= 0) {
    throw input_error(path, line.line_number, "the 3x3 part is not a rotation matrix");
  }
}

std::string format_line(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string format_line(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list args_copy;
  va_copy(args_copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  std::string text(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(text.data(), text.size() + 1, format, args_copy);
  va_end(args_copy);
  return text;
}

}  // namespace

Trajectory read_tum_trajectory(const std::string& path) {
  Trajectory trajectory;
  for (const DataLine& line : read_data_lines(path)) {
    require_fields(path, line, 8, "timestamp tx ty tz qx qy qz qw");
    double v[8];
    for (std::size_t k = 0; k < 8; ++k) v[k] = number(path, line, k);
    const Eigen::Quaterniond q = quaternion(path, line, v[7], v[4], v[5], v[6]);
    trajectory.push_back({v[0], SE3(q, Vec3(v[1], v[2], v[3]))});
  }
  return trajectory;
}

Trajectory read_kitti_trajectory(const std::string& path, const std::vector<double>& timestamps) {
  const std::vector<DataLine> lines = read_data_lines(path);
  if (!timestamps.empty() && timestamps.size() != lines.size()) {
    throw input_error(path, std::to_string(lines.size()) + " poses but " + std::to_string(timestamps.size()) +
                                " timestamps were given");
  }
  Trajectory trajectory;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const DataLine& line = lines[i];
    require_fields(path, line, 12, "3x4 matrix, row-major");
    if (line.fields.size() > 12) {
      throw input_error(
          path, line.line_number,
          "expected 12 fields (3x4 matrix, row-major), got " + std::to_string(line.fields.size()));
    }
    Mat3 rotation;
    Vec3 translation;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation(r, c) = number(path, line, static_cast<std::size_t>(4 * r + c));
      translation(r) = number(path, line, static_cast<std::size_t>(4 * r + 3));
    }
    check_rotation(path, line, rotation);
    const double stamp = timestamps.empty() ? static_cast<double>(i) : timestamps[i];
    trajectory.push_back({stamp, SE3(rotation, translation)});
  }
  return trajectory;
}

Trajectory read_euroc_trajectory(const std::string& path) {
  Trajectory trajectory;
  for (const DataLine& line : read_data_lines(path)) {
    require_fields(path, line, 8, "timestamp[ns], p x y z, q w x y z");
    const double stamp = euroc_stamp_s(path, line);
    double v[8];
    for (std::size_t k = 1; k < 8; ++k) v[k] = number(path, line, k);
    const Eigen::Quaterniond q = quaternion(path, line, v[4], v[5], v[6], v[7]);
    trajectory.push_back({stamp, SE3(q, Vec3(v[1], v[2], v[3]))});
  }
  return trajectory;
}

TrajectoryFormat detect_trajectory_format(const std::string& path) {
  const std::vector<std::string> lines = read_lines(path);
  for (const std::string& line : lines) {
    const std::string trimmed = trim(line);
    if (trimmed.empty()) continue;
    if (trimmed.front() == '#') {
      if (trimmed.find("[ns]") != std::string::npos) return TrajectoryFormat::kEuroc;
      continue;
    }
    const std::vector<std::string> fields = split_fields(trimmed, true);
    const bool commas = trimmed.find(',') != std::string::npos;
    const std::optional<double> first = fields.empty() ? std::nullopt : parse_double(fields[0]);
    if (commas && fields.size() >= 8 && first && std::abs(*first) >= kEurocStampThreshold) {
      return TrajectoryFormat::kEuroc;
    }
    return fields.size() == 12 ? TrajectoryFormat::kKitti : TrajectoryFormat::kTum;
  }
  return TrajectoryFormat::kTum;
}

const char* to_string(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "kitti";
    case TrajectoryFormat::kEuroc:
      return "euroc";
  }
  return "unknown";
}

Trajectory read_trajectory(const std::string& path) {
  switch (detect_trajectory_format(path)) {
    case TrajectoryFormat::kEuroc:
      return read_euroc_trajectory(path);
    case TrajectoryFormat::kKitti: {
      // KITTI layout: poses.txt beside times.txt, one line each per frame.
      const auto times = std::filesystem::path(path).parent_path() / "times.txt";
      if (!std::filesystem::is_regular_file(times)) {
        spdlog::warn("{}: KITTI poses without a times.txt beside them: the line index is the timestamp", path);
        return read_kitti_trajectory(path);
      }
      std::vector<double> stamps;
      for (const auto& entry : read_times_list(times.string())) stamps.push_back(entry.timestamp_s);
      return read_kitti_trajectory(path, stamps);
    }
    case TrajectoryFormat::kTum:
      break;
  }
  return read_tum_trajectory(path);
}

TrajectoryFormat parse_trajectory_format(const std::string& name) {
  if (name == "kitti") return TrajectoryFormat::kKitti;
  if (name == "euroc") return TrajectoryFormat::kEuroc;
  return TrajectoryFormat::kTum;
}

std::string trajectory_header(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "# timestamp tx ty tz qx qy qz qw\n";
    case TrajectoryFormat::kKitti:
      return "";
    case TrajectoryFormat::kEuroc:
      return "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n";
  }
  return "";
}

std::string format_trajectory_line(const StampedPose& pose, TrajectoryFormat format) {
  const Vec3& t = pose.world_from_cam.translation();
  switch (format) {
    case TrajectoryFormat::kKitti: {
      const Mat3 r = pose.world_from_cam.rotation_matrix();
      return format_line("%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", r(0, 0), r(0, 1), r(0, 2),
                         t(0), r(1, 0), r(1, 1), r(1, 2), t(1), r(2, 0), r(2, 1), r(2, 2), t(2));
    }
    case TrajectoryFormat::kEuroc: {
      const Eigen::Quaterniond q = pose.world_from_cam.rotation().normalized();
      const long long stamp_ns = std::llround(pose.timestamp_s * 1e9);
      return format_line("%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n", stamp_ns, t.x(), t.y(), t.z(), q.w(), q.x(),
                         q.y(), q.z());
    }
    case TrajectoryFormat::kTum:
      break;
  }
  const Eigen::Quaterniond q = pose.world_from_cam.rotation().normalized();
  return format_line("%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", pose.timestamp_s, t.x(), t.y(), t.z(), q.x(),
                     q.y(), q.z(), q.w());
}

namespace {
void write_formatted(const std::string& path, const Trajectory& trajectory, TrajectoryFormat format) {
  AtomicFile file(path);
  file.stream() << trajectory_header(format);
  for (const StampedPose& pose : trajectory) file.stream() << format_trajectory_line(pose, format);
  file.commit();
}
}  // namespace

void write_tum_trajectory(const std::string& path, const Trajectory& trajectory) {
  write_formatted(path, trajectory, TrajectoryFormat::kTum);
}

void write_kitti_trajectory(const std::string& path, const Trajectory& trajectory) {
  write_formatted(path, trajectory, TrajectoryFormat::kKitti);
}

void write_euroc_trajectory(const std::string& path, const Trajectory& trajectory) {
  write_formatted(path, trajectory, TrajectoryFormat::kEuroc);
}

void write_trajectory(const std::string& path, const Trajectory& trajectory, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      write_tum_trajectory(path, trajectory);
      return;
    case TrajectoryFormat::kKitti:
      write_kitti_trajectory(path, trajectory);
      return;
    case TrajectoryFormat::kEuroc:
      write_euroc_trajectory(path, trajectory);
      return;
  }
}

}  // namespace crowdslam::io
