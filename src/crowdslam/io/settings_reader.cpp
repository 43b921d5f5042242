#include "crowdslam/io/settings_reader.h"

#include <spdlog/spdlog.h>

#include <cassert>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>

#include "crowdslam/io/input_text.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::io {
namespace {

constexpr std::size_t kMaxUnknownKeyWarnings = 10;

struct KeyLine {
  std::string key;
  int line = 0;
  std::string value;  // as written, comment removed
};

// Top-level "key: value" lines (column 0, not a comment or a YAML directive). Lines that are not keys
// (e.g. the continuation of a flow list) are filtered out later against cv::FileStorage's own keys.
std::vector<KeyLine> top_level_keys(const std::vector<std::string>& lines) {
  std::vector<KeyLine> keys;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& text = lines[i];
    if (text.empty() || text[0] == ' ' || text[0] == '\t' || text[0] == '#' || text[0] == '%' ||
        text[0] == '-' || text[0] == '.')
      continue;
    const auto colon = text.find(':');
    if (colon == std::string::npos) continue;
    std::string key = trim(text.substr(0, colon));
    if (key.size() >= 2 && (key.front() == '"' || key.front() == '\'') && key.back() == key.front())
      key = key.substr(1, key.size() - 2);
    std::string value = text.substr(colon + 1);
    if (const auto hash = value.find(" #"); hash != std::string::npos) value.resize(hash);
    keys.push_back({key, static_cast<int>(i + 1), trim(value)});
  }
  return keys;
}

// A closer known (or accepted) key: by edit distance, or the known key an ORB-SLAM3 style "Section.Key"
// ends with (RGBD.DepthMapFactor -> DepthMapFactor).
std::string suggestion_for(const std::string& key) {
  const std::size_t limit = key.size() <= 6 ? 1 : key.size() <= 12 ? 2 : 3;
  std::string best;
  std::size_t best_distance = limit + 1;
  for (const std::string& known : known_settings_keys()) {
    const std::size_t d = edit_distance(key, known);
    if (d < best_distance) {
      best_distance = d;
      best = known;
    }
  }
  if (!best.empty()) return best;
  const auto dot = key.find('.');
  if (dot != std::string::npos) {
    const std::string rest = key.substr(dot + 1);
    for (const std::string& known : known_settings_keys())
      if (known == rest) return known;
  }
  return {};
}

// A plain decimal integer literal ("123", "-4", not "010" or "0x1F"), as a double (no overflow).
std::optional<double> decimal_integer(const std::string& text) {
  std::size_t start = (!text.empty() && (text[0] == '-' || text[0] == '+')) ? 1 : 0;
  if (start >= text.size()) return std::nullopt;
  for (std::size_t i = start; i < text.size(); ++i)
    if (text[i] < '0' || text[i] > '9') return std::nullopt;
  if (text[start] == '0' && text.size() > start + 1) return std::nullopt;
  return std::strtod(text.c_str(), nullptr);
}

}  // namespace

SettingsReader::SettingsReader(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  const auto status = std::filesystem::status(path_, ec);
  if (status.type() == std::filesystem::file_type::not_found)
    throw input_error(clip_text(path_), "settings file does not exist");
  if (ec) throw input_error(clip_text(path_), "cannot access settings file: " + ec.message());
  if (!std::filesystem::is_regular_file(status))
    throw input_error(clip_text(path_), "settings path is not a regular file");
  try {
    storage_.open(path_, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw input_error(clip_text(path_),
                      std::string("cannot parse settings (YAML starting with %YAML:1.0 expected): ") + e.err);
  }
  if (!storage_.isOpened()) throw input_error(clip_text(path_), "cannot open settings file");
  scan_keys();
}

void SettingsReader::scan_keys() {
  std::multiset<std::string> parsed;  // the top-level keys cv::FileStorage found
  const cv::FileNode root = storage_.root();
  if (root.isMap())
    for (auto it = root.begin(); it != root.end(); ++it) parsed.insert((*it).name());
  std::map<std::string, int> first_line;
  std::size_t unknown = 0;
  const std::string file = clip_text(path_);
  for (const KeyLine& k : top_level_keys(read_lines(path_))) {
    if (parsed.count(k.key) == 0) continue;  // not a key after all
    if (const auto [it, inserted] = first_line.emplace(k.key, k.line); !inserted)
      throw input_error(file, k.line,
                        clip_text(k.key) + ": set twice (first on line " + std::to_string(it->second) + ")");
    raw_values_[k.key] = k.value;
    if (is_accepted_settings_key(k.key)) continue;
    if (++unknown > kMaxUnknownKeyWarnings) continue;
    const std::string suggestion = suggestion_for(k.key);
    warnings_.push_back(file + ":" + std::to_string(k.line) + ": " + clip_text(k.key) +
                        ": unknown key, ignored" +
                        (suggestion.empty() ? std::string() : " (did you mean " + suggestion + "?)"));
  }
  // Keys cv::FileStorage parsed that the line scan did not see (unusual YAML layout): no line to give.
  for (const std::string& key : parsed) {
    if (first_line.count(key) || is_accepted_settings_key(key)) continue;
    first_line.emplace(key, 0);
    if (++unknown > kMaxUnknownKeyWarnings) continue;
    const std::string suggestion = suggestion_for(key);
    warnings_.push_back(file + ": " + clip_text(key) + ": unknown key, ignored" +
                        (suggestion.empty() ? std::string() : " (did you mean " + suggestion + "?)"));
  }
  if (unknown > kMaxUnknownKeyWarnings)
    warnings_.push_back(file + ": " + std::to_string(unknown - kMaxUnknownKeyWarnings) +
                        " more unknown keys ignored");
  for (const std::string& w : warnings_) spdlog::warn("{}", w);
}

void SettingsReader::fail(const std::string& key, const std::string& reason) const {
  throw input_error(clip_text(path_), key + ": " + reason);
}

cv::FileNode SettingsReader::node(const std::string& key) const {
  assert(is_accepted_settings_key(key) && "add the key to known_settings_keys()");
  try {
    return storage_[key];
  } catch (const cv::Exception& e) {
    fail(key, std::string("cannot read: ") + e.err);
  }
}

bool SettingsReader::has(const std::string& key) const {
  const cv::FileNode n = node(key);
  return !n.empty() && !n.isNone();
}

std::optional<double> SettingsReader::real(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  const cv::FileNode n = node(key);
  if (!n.isReal() && !n.isInt()) fail(key, "expected a number");
  double value = n.isInt() ? static_cast<double>(static_cast<int>(n)) : static_cast<double>(n);
  if (n.isInt()) {  // cv::FileStorage wraps integers beyond 32 bits; take the value as written
    const auto raw = raw_values_.find(key);
    if (raw != raw_values_.end())
      if (const auto written = decimal_integer(raw->second)) value = *written;
  }
  if (!std::isfinite(value)) fail(key, "value is not finite");
  return value;
}

std::optional<int> SettingsReader::integer(const std::string& key) const {
  const auto value = real(key);
  if (!value) return std::nullopt;
  if (std::floor(*value) != *value) fail(key, "expected an integer");
  if (*value < INT_MIN || *value > INT_MAX) {
    const auto raw = raw_values_.find(key);
    const std::string written = raw != raw_values_.end() ? clip_text(raw->second) : std::to_string(*value);
    fail(key, written + " is out of range for an integer (" + std::to_string(INT_MIN) + ".." +
                  std::to_string(INT_MAX) + ")");
  }
  return static_cast<int>(*value);
}

std::optional<bool> SettingsReader::flag(const std::string& key) const {
  if (has(key) && !node(key).isReal() && !node(key).isInt()) {
    const cv::FileNode n = node(key);
    fail(key, "expected 0 or 1 (off or on), got " +
                  (n.isString() ? "'" + clip_text(static_cast<std::string>(n), 60) + "'" : std::string("a non-number")));
  }
  const auto value = integer(key);
  if (!value) return std::nullopt;
  if (*value != 0 && *value != 1) fail(key, "expected 0 or 1, got " + std::to_string(*value));
  return *value == 1;
}

std::optional<std::string> SettingsReader::text(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  const cv::FileNode n = node(key);
  if (!n.isString()) fail(key, "expected a string");
  return static_cast<std::string>(n);
}

std::optional<std::vector<double>> SettingsReader::reals(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  const cv::FileNode n = node(key);
  if (!n.isSeq()) fail(key, "expected a list of numbers like [0, 0.5]");
  std::vector<double> values;
  for (const auto& item : n) {
    if (!item.isReal() && !item.isInt()) fail(key, "expected a list of numbers like [0, 0.5]");
    values.push_back(item.isInt() ? static_cast<double>(static_cast<int>(item)) : static_cast<double>(item));
    if (!std::isfinite(values.back())) fail(key, "value is not finite");
  }
  return values;
}

std::optional<cv::Mat> SettingsReader::matrix(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  const cv::FileNode n = node(key);
  cv::Mat m;
  try {
    if (!n.isMap()) throw cv::Exception();
    n >> m;
  } catch (const cv::Exception&) {
    fail(key, "expected an opencv-matrix (rows, cols, dt, data)");
  }
  if (m.empty() || m.channels() != 1) fail(key, "expected a non-empty single-channel opencv-matrix");
  cv::Mat result;
  m.convertTo(result, CV_64F);
  if (!cv::checkRange(result)) fail(key, "matrix has non-finite values");
  return result;
}

double SettingsReader::required_real(const std::string& key) const {
  const auto value = real(key);
  if (!value) fail(key, "missing");
  return *value;
}

int SettingsReader::required_integer(const std::string& key) const {
  const auto value = integer(key);
  if (!value) fail(key, "missing");
  return *value;
}

cv::Mat SettingsReader::required_matrix(const std::string& key) const {
  auto value = matrix(key);
  if (!value) fail(key, "missing");
  return *value;
}

}  // namespace crowdslam::io
