#include "crowdslam/util/error.h"

namespace crowdslam {

InputError input_error(const std::string& file, const std::string& message) {
  return InputError(file + ": " + message);
}

InputError input_error(const std::string& file, int line, const std::string& message) {
  if (line <= 0) return input_error(file, message);
  return InputError(file + ":" + std::to_string(line) + ": " + message);
}

}  // namespace crowdslam
