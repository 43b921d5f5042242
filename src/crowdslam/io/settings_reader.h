#pragma once
// Typed access to the keys of a cv::FileStorage settings file (internal to io/settings*.cpp).
// Every value failure is InputError "FILE: KEY: reason".
//
// Opening also scans the file's top-level keys with their lines (cv::FileStorage has no line numbers):
//   - a key set twice is an error "FILE:LINE: KEY: set twice (first on line N)" (cv::FileStorage would
//     silently use one of them);
//   - an unknown key is warned about (spdlog::warn) as "FILE:LINE: KEY: unknown key, ignored (did you mean
//     Camera.fx?)", the suggestion being the closest known key by edit distance; ORB-SLAM2/3 keys that
//     crowdslam does not use (Viewer.*, Camera.type, Camera.bFishEye, IMU.*, ...) are accepted silently;
//   - integer literals too large for cv::FileStorage (which wraps "100000000000000000000" to -1) keep
//     their written value, so they are reported as out of range instead of as a wrong number.
#include <map>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace crowdslam::io {

class SettingsReader {
 public:
  explicit SettingsReader(std::string path);  // opens the file; throws InputError naming it

  [[nodiscard]] bool has(const std::string& key) const;
  [[nodiscard]] std::optional<double> real(const std::string& key) const;
  [[nodiscard]] std::optional<int> integer(const std::string& key) const;
  [[nodiscard]] std::optional<bool> flag(const std::string& key) const;  // 0 or 1
  [[nodiscard]] std::optional<std::string> text(const std::string& key) const;
  [[nodiscard]] std::optional<std::vector<double>> reals(const std::string& key) const;
  [[nodiscard]] std::optional<cv::Mat> matrix(const std::string& key) const;  // opencv-matrix -> CV_64F

  [[nodiscard]] double required_real(const std::string& key) const;
  [[nodiscard]] int required_integer(const std::string& key) const;
  [[nodiscard]] cv::Mat required_matrix(const std::string& key) const;

  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;

  // The messages warned about at opening (unknown keys), for tests and callers that report them.
  [[nodiscard]] const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  [[nodiscard]] cv::FileNode node(const std::string& key) const;
  void scan_keys();

  std::string path_;
  cv::FileStorage storage_;
  std::map<std::string, std::string> raw_values_;  // top-level key -> value text as written
  std::vector<std::string> warnings_;
};

// Every key load_settings reads, and whether `key` is one of them or an accepted ORB-SLAM2/3 key.
const std::vector<std::string>& known_settings_keys();
bool is_accepted_settings_key(const std::string& key);

}  // namespace crowdslam::io
