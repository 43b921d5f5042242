#pragma once
// The page template and its script (assets/report.html, assets/report.js), embedded at build time
// (CMake writes report_assets.cpp from report_assets.cpp.in): the binary needs no source tree to run.
namespace crowdslam::report {

const char* report_html_template();  // placeholders: CROWDSLAM_TITLE, the three /*CROWDSLAM_...*/ comments
const char* report_script();

}  // namespace crowdslam::report
