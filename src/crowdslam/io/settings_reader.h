#pragma once
// Typed access to the keys of a cv::FileStorage settings file (internal to io/settings*.cpp).
// Every failure is InputError "FILE: KEY: reason".
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

 private:
  [[nodiscard]] cv::FileNode node(const std::string& key) const;

  std::string path_;
  cv::FileStorage storage_;
};

}  // namespace crowdslam::io
