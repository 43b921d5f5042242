#pragma once
// The data a report page embeds (one JSON document in a <script type="application/json"> block), built
// from the runs read by load_run. Everything the page draws is in it; the page computes nothing but
// the chart layout. Numbers are rounded to what a chart can show (0.1 mm, 1 us) to keep the file small.
#include <nlohmann/json.hpp>
#include <vector>

#include "crowdslam/report/frame_strip.h"
#include "crowdslam/report/run_data.h"

namespace crowdslam::report {

// The two views of the trajectories: "top" (the two axes along which the ground truth, or without it the
// first run's trajectory, extends most) and "side" (the longest and the shortest axis). Axes 0 = x,
// 1 = y, 2 = z of the ground truth's frame.
struct ViewAxes {
  int top[2] = {0, 2};
  int side[2] = {0, 1};
};
ViewAxes choose_view_axes(const io::Trajectory& reference);

// The summary table: row labels in order, and one formatted value per row for a run.
const std::vector<std::string>& summary_rows();
std::vector<std::string> summary_values(const RunData& run);

// One run's part of the page data.
nlohmann::json run_page_data(const RunData& run, const FrameStripOptions& strip);

// The whole document: {"title", "generated", "axes", "summary_rows", "runs": [...]}.
nlohmann::json page_data(const std::vector<RunData>& runs, const FrameStripOptions& strip);

// The ground truth within the run's time span (0.5 s either side), at most `max_poses` (evenly thinned).
io::Trajectory ground_truth_in_span(const RunData& run, size_t max_poses = 4000);

}  // namespace crowdslam::report
