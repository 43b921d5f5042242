#pragma once
// Error types shared by every module.
//
// InputError: something the user gave us (file, setting, argument) is wrong. The message names the
// file, and where known the line and key, so the app can print it as one line and exit non-zero.
// Programming errors are asserts, not exceptions.
#include <stdexcept>
#include <string>

namespace crowdslam {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

// "FILE: message", "FILE:LINE: message" (line 0 = unknown).
[[nodiscard]] InputError input_error(const std::string& file, const std::string& message);
[[nodiscard]] InputError input_error(const std::string& file, int line, const std::string& message);

}  // namespace crowdslam
