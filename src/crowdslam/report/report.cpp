#include "crowdslam/report/report.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <utility>
#include <vector>

#include "crowdslam/report/chartjs.h"
#include "crowdslam/report/page_data.h"
#include "crowdslam/report/report_assets.h"
#include "crowdslam/report/run_data.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::report {

namespace {

// The template with each placeholder replaced by its value. The placeholders are found in the template
// itself, so a value (user data, Chart.js) is never searched for the others.
std::string fill_template(const std::string& text,
                          const std::vector<std::pair<std::string, std::string>>& values) {
  std::vector<std::pair<size_t, size_t>> at;  // position in `text`, index into `values`
  for (size_t k = 0; k < values.size(); ++k) {
    const auto pos = text.find(values[k].first);
    assert(pos != std::string::npos);  // the template is ours
    at.emplace_back(pos, k);
  }
  std::sort(at.begin(), at.end());
  std::string out;
  size_t copied = 0;
  for (const auto& [pos, k] : at) {
    out.append(text, copied, pos - copied);
    out += values[k].second;
    copied = pos + values[k].first.size();
  }
  out.append(text, copied, std::string::npos);
  return out;
}

std::string html_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Runs are told apart by their labels (legend, table): "a/out" and "b/out" become "a/out" and "b/out",
// the same directory twice "out" and "out (2)".
void make_labels_unique(std::vector<RunData>& runs) {
  std::vector<std::string> repeated;
  for (const auto& run : runs) {
    if (std::count_if(runs.begin(), runs.end(), [&](const RunData& r) { return r.label == run.label; }) > 1) {
      repeated.push_back(run.label);
    }
  }
  for (auto& run : runs) {
    if (std::find(repeated.begin(), repeated.end(), run.label) == repeated.end()) continue;
    const auto parent =
        std::filesystem::absolute(run.dir).lexically_normal().parent_path().filename().string();
    if (!parent.empty()) run.label = parent + "/" + run.label;
  }
  for (size_t k = 1; k < runs.size(); ++k) {
    int suffix = 2;
    const std::string base = runs[k].label;
    while (std::any_of(runs.begin(), runs.begin() + static_cast<std::ptrdiff_t>(k),
                       [&](const RunData& r) { return r.label == runs[k].label; })) {
      runs[k].label = base + " (" + std::to_string(suffix++) + ")";
    }
  }
}

}  // namespace

std::string script_safe_source(std::string source) {
  // "<\/script" means the same as "</script" in JavaScript strings and regular expressions, and does not
  // end the element.
  for (size_t pos = 0; (pos = source.find("</script", pos)) != std::string::npos; pos += 2) {
    source.replace(pos, 2, "<\\/");
  }
  return source;
}

std::string script_safe_json(const std::string& json_text) {
  std::string out;
  out.reserve(json_text.size());
  for (const char c : json_text) {
    if (c == '<') {
      out += "\\u003c";  // '<' only occurs inside JSON strings, where \u003c means the same
    } else {
      out += c;
    }
  }
  return out;
}

std::string render_page(const nlohmann::json& page_data, const std::string& chartjs_source) {
  const std::string title = page_data.value("title", std::string("crowdslam report"));
  return fill_template(
      report_html_template(),
      {{"CROWDSLAM_TITLE", html_escape(title)},
       {"/*CROWDSLAM_CHARTJS*/", script_safe_source(chartjs_source)},
       {"/*CROWDSLAM_REPORT_SCRIPT*/", script_safe_source(report_script())},
       {"/*CROWDSLAM_DATA*/",
        script_safe_json(page_data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace))}});
}

ReportResult write_report(const std::filesystem::path& run_dir,
                          const std::vector<std::filesystem::path>& compare_dirs,
                          const std::filesystem::path& html_out, const ReportOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  options.check();
  // Chart.js first: without it there is no page to write, whatever the runs hold.
  const std::string chartjs = read_chartjs(options.chartjs.empty() ? chartjs_path() : options.chartjs);
  std::vector<RunData> runs;
  runs.push_back(load_run(run_dir));
  for (const auto& dir : compare_dirs) runs.push_back(load_run(dir));
  make_labels_unique(runs);
  FrameStripOptions strip = options.frames;
  if (runs.size() > 1 && strip.max_frames > 0)
    strip.max_frames = std::max<size_t>(1, strip.max_frames / runs.size());
  const nlohmann::json data = page_data(runs, strip);
  size_t frames_embedded = 0;
  for (const auto& run : data["runs"]) frames_embedded += run["saved_frames"].size();
  const std::string page = render_page(data, chartjs);
  write_file_atomic(html_out, page);
  ReportResult result;
  result.path = html_out;
  result.bytes = page.size();
  result.runs = runs.size();
  result.frames_embedded = frames_embedded;
  result.write_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("report: {} ({} KiB, {} run{}, {} saved frames, {:.0f} ms)", clip_text(html_out.string()),
               result.bytes / 1024, result.runs, result.runs > 1 ? "s" : "", frames_embedded,
               result.write_ms);
  return result;
}

}  // namespace crowdslam::report
