#pragma once
// report.html: one self-contained page about one finished run, or several overlaid (--compare).
//
// It opens from disk with no server and no network: Chart.js (Debian's libjs-chart.js, see chartjs.h)
// and the page's own script are inlined, the data is one JSON block (page_data.h), saved frames are
// JPEG data URLs. Contents: summary table (one column per run), trajectory against the ground truth from
// above and from the side (aligned as run.json's ATE), translation error over time, per-frame time by
// stage, local mapping per keyframe, people coverage, feature budget and keypoints kept/removed,
// tracking state and method timeline (relocalisations, loops and map resets marked), saved frames.
//
// The page reports itself for tests: <body data-charts="N" data-charts-expected="M" data-errors="E">
// after drawing (E counts JavaScript errors, window.onerror).
//
// The report reads only files (OUT/run.json, the trajectories, OUT/frames/, the dataset's ground truth):
// it works for any finished run and knows nothing of the system that made it.
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "crowdslam/report/frame_strip.h"

namespace crowdslam::report {

struct ReportOptions {
  FrameStripOptions frames;       // the strip of saved frames, per run
  std::filesystem::path chartjs;  // empty: chartjs_path() ($CROWDSLAM_CHARTJS or the Debian file)
  void check() const { frames.check(); }
};

struct ReportResult {
  std::filesystem::path path;
  size_t bytes = 0;
  size_t runs = 0;
  size_t frames_embedded = 0;
  double write_ms = 0;  // reading the runs, building and writing the page
};

// Reads `run_dir` (and each of `compare_dirs`, overlaid) and writes the page atomically to `html_out`.
// Throws InputError naming the file and key for bad input (run_data.h), and for a missing Chart.js.
ReportResult write_report(const std::filesystem::path& run_dir,
                          const std::vector<std::filesystem::path>& compare_dirs,
                          const std::filesystem::path& html_out, const ReportOptions& options = {});

// The page for already-built data (page_data.h) around `chartjs_source`; for tests.
std::string render_page(const nlohmann::json& page_data, const std::string& chartjs_source);

// JavaScript safe inside <script>...</script>: "</script" written as "<\/script".
std::string script_safe_source(std::string source);

// JSON text safe inside <script type="application/json">: every '<' written as \u003c.
std::string script_safe_json(const std::string& json_text);

}  // namespace crowdslam::report
