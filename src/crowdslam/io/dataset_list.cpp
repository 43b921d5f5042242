#include "crowdslam/io/dataset_list.h"

#include <cmath>
#include <filesystem>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::io {
namespace {

std::vector<std::string> lines_of(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw input_error(path, "list file does not exist");
  return read_lines(path);
}

double parse_stamp(const std::string& field, const std::string& path, int line) {
  const auto value = parse_double(field);
  if (!value || !std::isfinite(*value))
    throw input_error(path, line, "timestamp '" + field + "' is not a finite number");
  return *value;
}

}  // namespace

bool is_comment_or_blank(const std::string& line) {
  const std::string t = trim(line);
  return t.empty() || t[0] == '#';
}

std::vector<ListEntry> read_tum_list(const std::string& path) {
  std::vector<ListEntry> entries;
  const auto lines = lines_of(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (is_comment_or_blank(lines[i])) continue;
    const int line = static_cast<int>(i + 1);
    const auto fields = split_fields(lines[i], false);
    if (fields.size() < 2)
      throw input_error(path, line, "expected 'timestamp filename', got '" + trim(lines[i]) + "'");
    entries.push_back({parse_stamp(fields[0], path, line), 0, fields[1], line});
  }
  if (entries.empty()) throw input_error(path, "list is empty");
  return entries;
}

std::vector<ListEntry> read_euroc_list(const std::string& path) {
  std::vector<ListEntry> entries;
  const auto lines = lines_of(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (is_comment_or_blank(lines[i])) continue;
    const int line = static_cast<int>(i + 1);
    const auto fields = split_fields(lines[i], true);
    if (fields.size() < 2)
      throw input_error(path, line, "expected 'timestamp_ns,filename', got '" + trim(lines[i]) + "'");
    const auto ns = parse_int(fields[0]);
    if (!ns || *ns < 0)
      throw input_error(path, line, "timestamp '" + fields[0] + "' is not an integer number of ns");
    // Seconds and nanoseconds apart, as io::read_euroc_trajectory does, so equal ns give equal doubles.
    const double stamp_s =
        static_cast<double>(*ns / 1000000000LL) + static_cast<double>(*ns % 1000000000LL) * 1e-9;
    entries.push_back({stamp_s, *ns, fields[1], line});
  }
  if (entries.empty()) throw input_error(path, "list is empty");
  return entries;
}

std::vector<ListEntry> read_times_list(const std::string& path) {
  std::vector<ListEntry> stamps;
  const auto lines = lines_of(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (is_comment_or_blank(lines[i])) continue;
    const int line = static_cast<int>(i + 1);
    const auto fields = split_fields(lines[i], false);
    if (fields.size() != 1)
      throw input_error(path, line, "expected one timestamp, got '" + trim(lines[i]) + "'");
    stamps.push_back({parse_stamp(fields[0], path, line), 0, {}, line});
  }
  if (stamps.empty()) throw input_error(path, "list is empty");
  return stamps;
}

void require_listed_file(const std::string& file, const std::string& list, int line) {
  if (!std::filesystem::is_regular_file(file))
    throw input_error(list, line, "listed image " + file + " does not exist");
}

}  // namespace crowdslam::io
