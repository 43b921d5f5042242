#include "crowdslam/report/chartjs.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

#ifndef CROWDSLAM_CHARTJS_PATH
#define CROWDSLAM_CHARTJS_PATH "/usr/share/javascript/chart.js/chart.min.js"
#endif

namespace crowdslam::report {

std::filesystem::path chartjs_path() {
  const char* from_env = std::getenv("CROWDSLAM_CHARTJS");
  if (from_env != nullptr && *from_env != '\0') return from_env;
  return CROWDSLAM_CHARTJS_PATH;
}

std::string read_chartjs(const std::filesystem::path& path) {
  const std::string name = clip_text(path.string());
  const std::string hint =
      " (the report inlines Chart.js: install the Debian package libjs-chart.js, `apt-get install "
      "libjs-chart.js`, "
      "or point CROWDSLAM_CHARTJS at Chart.js's UMD build, chart.min.js or chart.umd.js)";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw input_error(name, "Chart.js not found" + hint);
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in || text.str().empty()) throw input_error(name, "Chart.js could not be read or is empty" + hint);
  return text.str();
}

}  // namespace crowdslam::report
