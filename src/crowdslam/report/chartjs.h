#pragma once
// Chart.js, inlined into every report: the UMD build from Debian's libjs-chart.js (it defines
// window.Chart). $CROWDSLAM_CHARTJS overrides the path compiled in (CROWDSLAM_CHARTJS_PATH).
#include <filesystem>
#include <string>

namespace crowdslam::report {

// $CROWDSLAM_CHARTJS when set and not empty, else the Debian path.
std::filesystem::path chartjs_path();

// The file's contents. Throws InputError naming the path and the package to install (libjs-chart.js)
// when it is missing, empty or unreadable.
std::string read_chartjs(const std::filesystem::path& path);

}  // namespace crowdslam::report
