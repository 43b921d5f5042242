#include "crowdslam/io/settings_reader.h"

#include <cmath>
#include <filesystem>

#include "crowdslam/util/error.h"

namespace crowdslam::io {

SettingsReader::SettingsReader(std::string path) : path_(std::move(path)) {
  if (!std::filesystem::is_regular_file(path_)) throw input_error(path_, "settings file does not exist");
  try {
    storage_.open(path_, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw input_error(path_,
                      std::string("cannot parse settings (YAML starting with %YAML:1.0 expected): ") + e.err);
  }
  if (!storage_.isOpened()) throw input_error(path_, "cannot open settings file");
}

void SettingsReader::fail(const std::string& key, const std::string& reason) const {
  throw input_error(path_, key + ": " + reason);
}

cv::FileNode SettingsReader::node(const std::string& key) const {
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
  const double value = n.isInt() ? static_cast<double>(static_cast<int>(n)) : static_cast<double>(n);
  if (!std::isfinite(value)) fail(key, "value is not finite");
  return value;
}

std::optional<int> SettingsReader::integer(const std::string& key) const {
  const auto value = real(key);
  if (!value) return std::nullopt;
  if (std::floor(*value) != *value || std::abs(*value) > 1e9) fail(key, "expected an integer");
  return static_cast<int>(*value);
}

std::optional<bool> SettingsReader::flag(const std::string& key) const {
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
