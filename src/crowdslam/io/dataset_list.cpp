#include "crowdslam/io/dataset_list.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <map>

#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::io {
namespace fs = std::filesystem;
namespace {

std::vector<std::string> lines_of(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) throw input_error(clip_text(path), "list file does not exist");
  if (ec) throw input_error(clip_text(path), "cannot access list file: " + ec.message());
  if (!fs::is_regular_file(status)) throw input_error(clip_text(path), "list file is not a regular file");
  return read_lines(path);
}

double parse_stamp(const std::string& field, const std::string& path, int line) {
  const auto value = parse_double(field);
  if (!value || !std::isfinite(*value))
    throw input_error(clip_text(path), line, "timestamp '" + clip_text(field) + "' is not a finite number");
  if (*value < 0 || *value >= kMaxTimestampS)
    throw input_error(clip_text(path), line,
                      "timestamp '" + clip_text(field) + "' is out of range (expected seconds in [0, 1e11))");
  return *value;
}

}  // namespace

bool is_comment_or_blank(const std::string& line) {
  const std::string t = trim(line);
  return t.empty() || t[0] == '#';
}

// Warns (once per list) when a time stamp is not after the one before it: a reversed or unsorted list
// is used, never silently.
static void warn_if_unordered(const std::vector<ListEntry>& entries, const std::string& path) {
  for (std::size_t i = 1; i < entries.size(); ++i) {
    if (entries[i].timestamp_s < entries[i - 1].timestamp_s) {
      spdlog::warn("{}:{}: time stamp {:.6f} is before the previous line's ({:.6f}); the list is not in time order",
                   clip_text(path), entries[i].line, entries[i].timestamp_s, entries[i - 1].timestamp_s);
      return;
    }
  }
}

std::vector<ListEntry> read_tum_list(const std::string& path) {
  std::vector<ListEntry> entries;
  const auto lines = lines_of(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (is_comment_or_blank(lines[i])) continue;
    const int line = static_cast<int>(i + 1);
    const auto fields = split_fields(lines[i], false);
    if (fields.size() < 2)
      throw input_error(clip_text(path), line,
                        "expected 'timestamp filename', got '" + clip_text(trim(lines[i])) + "'");
    entries.push_back({parse_stamp(fields[0], path, line), 0, fields[1], line});
  }
  if (entries.empty()) throw input_error(clip_text(path), "list is empty");
  warn_if_unordered(entries, path);
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
      throw input_error(clip_text(path), line,
                        "expected 'timestamp_ns,filename', got '" + clip_text(trim(lines[i])) + "'");
    const auto ns = parse_int(fields[0]);
    if (!ns || *ns < 0)
      throw input_error(clip_text(path), line,
                        "timestamp '" + clip_text(fields[0]) + "' is not a non-negative integer number of ns");
    // Seconds and nanoseconds apart, as io::read_euroc_trajectory does, so equal ns give equal doubles.
    const double stamp_s =
        static_cast<double>(*ns / 1000000000LL) + static_cast<double>(*ns % 1000000000LL) * 1e-9;
    entries.push_back({stamp_s, *ns, fields[1], line});
  }
  if (entries.empty()) throw input_error(clip_text(path), "list is empty");
  warn_if_unordered(entries, path);
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
      throw input_error(clip_text(path), line, "expected one timestamp, got '" + clip_text(trim(lines[i])) + "'");
    stamps.push_back({parse_stamp(fields[0], path, line), 0, {}, line});
  }
  if (stamps.empty()) throw input_error(clip_text(path), "list is empty");
  warn_if_unordered(stamps, path);
  return stamps;
}

void require_listed_file(const std::string& file, const std::string& list, int line, bool missing_ok) {
  std::error_code ec;
  const fs::file_status status = fs::status(file, ec);
  if (status.type() == fs::file_type::not_found && missing_ok) {
    spdlog::warn("{}:{}: listed image {} does not exist (its frame will be skipped)", clip_text(list), line,
                 clip_text(file));
    return;
  }
  if (status.type() == fs::file_type::not_found)
    throw input_error(clip_text(list), line, "listed image " + clip_text(file) + " does not exist");
  if (ec) throw input_error(clip_text(list), line, "listed image " + clip_text(file) + ": " + ec.message());
  if (!fs::is_regular_file(status))
    throw input_error(clip_text(list), line, "listed image " + clip_text(file) + " is not a regular file");
}

std::vector<ListEntry> without_duplicate_stamps(const std::vector<ListEntry>& entries,
                                                const std::string& list, bool by_ns) {
  std::map<double, std::size_t> by_seconds;
  std::map<long long, std::size_t> by_nanoseconds;
  std::size_t duplicates = 0;
  int first_repeat = 0;
  int first_original = 0;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    std::size_t* slot = nullptr;
    bool repeated = false;
    if (by_ns) {
      const auto [it, inserted] = by_nanoseconds.emplace(entries[i].timestamp_ns, i);
      slot = &it->second;
      repeated = !inserted;
    } else {
      const auto [it, inserted] = by_seconds.emplace(entries[i].timestamp_s, i);
      slot = &it->second;
      repeated = !inserted;
    }
    if (!repeated) continue;
    if (duplicates++ == 0) {
      first_repeat = entries[i].line;
      first_original = entries[*slot].line;
    }
    *slot = i;  // the later entry wins
  }
  if (duplicates > 0)
    spdlog::warn(
        "{}:{}: {} entr{} repeat a time stamp listed before (the first repeats line {}); of equal "
        "stamps the later entry is used, the earlier skipped (as TUM's associate.py does)",
        clip_text(list), first_repeat, duplicates, duplicates == 1 ? "y" : "ies", first_original);
  std::vector<ListEntry> kept;
  kept.reserve(entries.size() - duplicates);
  if (by_ns) {
    for (const auto& [stamp, index] : by_nanoseconds) kept.push_back(entries[index]);
  } else {
    for (const auto& [stamp, index] : by_seconds) kept.push_back(entries[index]);
  }
  return kept;
}

}  // namespace crowdslam::io
