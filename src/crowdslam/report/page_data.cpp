#include "crowdslam/report/page_data.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>

#include "crowdslam/eval/unique_stamps.h"
#include "crowdslam/report/json_fields.h"
#include "crowdslam/util/text.h"

namespace crowdslam::report {

namespace {

double rounded(double value, double step) { return std::round(value / step) * step; }

nlohmann::json rounded_array(const std::vector<double>& values, double step) {
  nlohmann::json out = nlohmann::json::array();
  for (const double v : values) out.push_back(rounded(v, step));
  return out;
}

// Positions as {"t": [...], "x": [...], "y": [...], "z": [...]}, t relative to `t0`.
nlohmann::json positions_json(const io::Trajectory& trajectory, double t0) {
  std::vector<double> t, x, y, z;
  for (const auto& pose : trajectory) {
    const auto p = pose.world_from_cam.translation();
    t.push_back(pose.timestamp_s - t0);
    x.push_back(p.x());
    y.push_back(p.y());
    z.push_back(p.z());
  }
  return {{"t", rounded_array(t, 1e-4)},
          {"x", rounded_array(x, 1e-4)},
          {"y", rounded_array(y, 1e-4)},
          {"z", rounded_array(z, 1e-4)}};
}

double first_stamp(const RunData& run) {
  return run.frames.size() > 0 ? run.frames.timestamp_s.front() : 0.0;
}

// Frame index (position in the series) nearest to `stamp`.
size_t nearest_frame(const FrameSeries& frames, double stamp) {
  const auto& t = frames.timestamp_s;
  const auto it = std::lower_bound(t.begin(), t.end(), stamp);
  if (it == t.begin()) return 0;
  if (it == t.end()) return t.size() - 1;
  const auto i = static_cast<size_t>(it - t.begin());
  return (stamp - t[i - 1] <= t[i] - stamp) ? i - 1 : i;
}

std::string number_or_dash(const nlohmann::json& value, const char* format) {
  if (!value.is_number()) return "-";
  return fmt::format(fmt::runtime(format), value.get<double>());
}

std::string ate_text(const RunData& run, const JsonFields& f) {
  const auto& accuracy = f.find("accuracy");
  if (!accuracy.is_object()) {
    return run.ground_truth_note.empty() ? "no ground truth"
                                         : "no ground truth (" + run.ground_truth_note + ")";
  }
  const auto& rmse = accuracy.value("ate_rmse_m", nlohmann::json());
  if (!rmse.is_number()) return "not evaluated: " + accuracy.value("error", std::string("?"));
  std::string text =
      fmt::format("{:.4f} m ({}, {} poses", rmse.get<double>(), accuracy.value("alignment", std::string("?")),
                  accuracy.value("ate_pairs", nlohmann::json(0)).get<long long>());
  if (run.segments.size() > 1)
    text += fmt::format(", map {} of {}", accuracy.value("map_id", -1), run.segments.size());
  return text + ")";
}

// Each keyframe's mapping time by step, as columns {"n": [...], "register": [...], ..., "total": [...]}, from
// run.json's local_mapping.keyframe_times_ms (null for runs written before it existed).
nlohmann::json keyframe_times(const JsonFields& f) {
  const auto& list = f.find("local_mapping.keyframe_times_ms");
  if (!list.is_array()) return nullptr;
  nlohmann::json columns;
  for (const char* key : {"n", "register", "triangulation", "fusion", "local_ba", "culling", "total"}) {
    nlohmann::json column = nlohmann::json::array();
    for (size_t k = 0; k < list.size(); ++k) {
      column.push_back(rounded(f.number_in(list[k], "local_mapping.keyframe_times_ms[" + std::to_string(k) + "]", key),
                               1e-3));
    }
    columns[key] = std::move(column);
  }
  return columns;
}

}  // namespace

ViewAxes choose_view_axes(const io::Trajectory& reference) {
  ViewAxes axes;
  if (reference.empty()) return axes;
  std::array<double, 3> low{}, high{};
  low.fill(1e300);
  high.fill(-1e300);
  for (const auto& pose : reference) {
    const auto p = pose.world_from_cam.translation();
    for (int a = 0; a < 3; ++a) {
      low[a] = std::min(low[a], p[a]);
      high[a] = std::max(high[a], p[a]);
    }
  }
  std::array<int, 3> order{0, 1, 2};
  // Longest extent first; ties keep x, y, z order.
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return high[a] - low[a] > high[b] - low[b]; });
  axes.top[0] = std::min(order[0], order[1]);
  axes.top[1] = std::max(order[0], order[1]);
  axes.side[0] = order[0];
  axes.side[1] = order[2];
  return axes;
}

const std::vector<std::string>& summary_rows() {
  static const std::vector<std::string> rows = {"end state",
                                                "dataset",
                                                "sensor, mode",
                                                "people filter",
                                                "frames",
                                                "tracked",
                                                "ATE RMSE",
                                                "RPE translation RMSE",
                                                "RPE rotation RMSE",
                                                "throughput",
                                                "frame time median / p95",
                                                "tracking median / p95",
                                                "extraction median",
                                                "detector wait median / p95",
                                                "mapping per keyframe median / p95",
                                                "keyframes",
                                                "map points",
                                                "loops closed",
                                                "relocalisations",
                                                "map resets",
                                                "wall time"};
  return rows;
}

std::vector<std::string> summary_values(const RunData& run) {
  const JsonFields f(run.document, (run.dir / "run.json").string());
  std::vector<std::string> v;
  v.push_back(f.text("end_state"));
  v.push_back(f.text("dataset"));
  const auto& mode = f.find("mode");
  v.push_back(f.text("sensor") + (mode.is_string() ? ", " + mode.get<std::string>() : ""));
  const auto& filter = f.find("people_filter");
  v.push_back(filter.is_object() ? fmt::format("{}, {} mode", filter.value("detector", std::string("?")),
                                               filter.value("mode", std::string("?")))
                                 : "off");
  v.push_back(fmt::format("{:.0f}", f.number("summary.frames")));
  v.push_back(fmt::format("{:.0f} ({:.1f} %)", f.number("summary.tracked_frames"),
                          f.number("summary.tracked_percent")));
  v.push_back(ate_text(run, f));
  v.push_back(number_or_dash(f.find("accuracy.rpe_trans_rmse_m_per_s"), "{:.4f} m/s"));
  v.push_back(number_or_dash(f.find("accuracy.rpe_rot_rmse_deg_per_s"), "{:.3f} deg/s"));
  v.push_back(fmt::format("{:.1f} frames/s", f.number("summary.throughput_fps")));
  v.push_back(fmt::format("{:.1f} / {:.1f} ms", f.number("summary.total_ms_median"),
                          f.number("summary.total_ms_p95")));
  v.push_back(number_or_dash(f.find("summary.tracking_ms_median"), "{:.1f}") + " / " +
              number_or_dash(f.find("summary.tracking_ms_p95"), "{:.1f} ms"));
  v.push_back(number_or_dash(f.find("summary.extraction_ms_median"), "{:.1f} ms"));
  v.push_back(filter.is_object()
                  ? number_or_dash(f.find("people_filter.detector_wait_ms_median"), "{:.1f}") + " / " +
                        number_or_dash(f.find("people_filter.detector_wait_ms_p95"), "{:.1f} ms")
                  : "-");
  v.push_back(number_or_dash(f.find("local_mapping.per_keyframe_ms.total.median"), "{:.1f}") + " / " +
              number_or_dash(f.find("local_mapping.per_keyframe_ms.total.p95"), "{:.1f} ms"));
  v.push_back(fmt::format("{:.0f}", f.number("summary.keyframes")));
  v.push_back(fmt::format("{:.0f}", f.number("summary.map_points")));
  const auto& loops = f.find("loop_closing.loops");
  v.push_back(loops.is_array() ? std::to_string(loops.size()) : "off");
  v.push_back(
      std::to_string(std::count(run.frames.method.begin(), run.frames.method.end(), "relocalization")));
  v.push_back(fmt::format("{:.0f}", f.number("summary.map_resets")));
  v.push_back(number_or_dash(f.find("summary.wall_time_s"), "{:.1f} s"));
  return v;
}

io::Trajectory ground_truth_in_span(const RunData& run, size_t max_poses) {
  io::Trajectory span;
  if (run.frames.size() == 0) return span;
  const double begin = run.frames.timestamp_s.front() - 0.5;
  const double end = run.frames.timestamp_s.back() + 0.5;
  for (const auto& pose : eval::unique_sorted_by_stamp(run.ground_truth)) {
    if (pose.timestamp_s >= begin && pose.timestamp_s <= end) span.push_back(pose);
  }
  if (span.size() <= max_poses) return span;
  io::Trajectory thinned;
  for (const size_t i : spread_indices(span.size(), max_poses)) thinned.push_back(span[i]);
  return thinned;
}

nlohmann::json run_page_data(const RunData& run, const FrameStripOptions& strip) {
  const JsonFields f(run.document, (run.dir / "run.json").string());
  const double t0 = first_stamp(run);
  nlohmann::json out;
  out["label"] = run.label;
  out["dir"] = run.dir.string();
  out["dataset"] = f.text("dataset");
  out["summary"] = summary_values(run);
  out["ground_truth_note"] = run.ground_truth_note;
  out["keyframes_note"] = run.keyframes_note;
  out["alignment"] = run.ground_truth.empty() ? "none" : eval::to_string(run.alignment);
  out["ground_truth"] =
      run.ground_truth.empty() ? nlohmann::json(nullptr) : positions_json(ground_truth_in_span(run), t0);

  nlohmann::json segments = nlohmann::json::array();
  for (const auto& s : run.segments) {
    nlohmann::json segment = {{"map_id", s.map_id},
                              {"aligned", s.ate.has_value()},
                              {"error", s.error},
                              {"poses", positions_json(s.aligned, t0)},
                              {"keyframes", positions_json(s.aligned_keyframes, t0)}};
    if (s.ate) {
      // Translation error of each matched pose, over time (the estimate's stamps, de-duplicated as eval
      // does).
      const io::Trajectory estimate = eval::unique_sorted_by_stamp(s.estimate);
      std::vector<double> t, e;
      for (size_t k = 0; k < s.ate->matches.size(); ++k) {
        t.push_back(estimate[s.ate->matches[k].second_index].timestamp_s - t0);
        e.push_back(s.ate->errors_m[k]);
      }
      segment["errors"] = {{"t", rounded_array(t, 1e-4)},
                           {"e", rounded_array(e, 1e-5)},
                           {"rmse", s.ate->translation_error_m.rmse},
                           {"scale", s.ate->alignment.scale}};
    }
    segments.push_back(std::move(segment));
  }
  out["segments"] = std::move(segments);
  out["evaluated_segment"] =
      run.evaluated_segment ? nlohmann::json(*run.evaluated_segment) : nlohmann::json(nullptr);

  const FrameSeries& fr = run.frames;
  std::vector<double> t;
  for (const double stamp : fr.timestamp_s) t.push_back(stamp - t0);
  std::vector<int> keyframe;
  for (const bool k : fr.keyframe) keyframe.push_back(k ? 1 : 0);
  out["frames"] = {{"index", fr.index},
                   {"t", rounded_array(t, 1e-4)},
                   {"extraction_ms", rounded_array(fr.extraction_ms, 1e-3)},
                   {"detector_wait_ms", rounded_array(fr.detector_wait_ms, 1e-3)},
                   {"tracking_ms", rounded_array(fr.tracking_ms, 1e-3)},
                   {"keypoints", fr.keypoints},
                   {"keypoints_before_filter", fr.keypoints_before_filter},
                   {"feature_budget", fr.feature_budget},
                   {"people_area", rounded_array(fr.people_area, 1e-4)},
                   {"person_boxes", fr.person_boxes},
                   {"tracked_points", fr.tracked_points},
                   {"state", fr.state},
                   {"method", fr.method},
                   {"keyframe", keyframe}};

  // Loops closed (at the frame nearest the keyframe's stamp) and map resets (first frame of each new map).
  nlohmann::json loops = nlohmann::json::array();
  const auto& loop_events = f.find("loop_closing.loops");
  if (loop_events.is_array() && fr.size() > 0) {
    for (size_t k = 0; k < loop_events.size(); ++k) {
      const double stamp =
          f.number_in(loop_events[k], "loop_closing.loops[" + std::to_string(k) + "]", "timestamp");
      const size_t i = nearest_frame(fr, stamp);
      loops.push_back({{"t", rounded(t[i], 1e-4)}, {"frame", fr.index[i]}});
    }
  }
  out["loops"] = std::move(loops);
  nlohmann::json resets = nlohmann::json::array();
  const auto& segment_info = f.array("segments");
  for (size_t k = 1; k < segment_info.size() && fr.size() > 0; ++k) {
    const double first_frame =
        f.number_in(segment_info[k], "segments[" + std::to_string(k) + "]", "first_frame");
    const auto it = std::lower_bound(fr.index.begin(), fr.index.end(), first_frame);
    const size_t i = it == fr.index.end() ? fr.size() - 1 : static_cast<size_t>(it - fr.index.begin());
    resets.push_back({{"t", rounded(t[i], 1e-4)}, {"frame", fr.index[i]}});
  }
  out["resets"] = std::move(resets);

  const auto& per_keyframe = f.find("local_mapping.per_keyframe_ms");
  if (per_keyframe.is_object()) {
    nlohmann::json mapping = {{"steps", nlohmann::json::array()},
                              {"median", nlohmann::json::array()},
                              {"p95", nlohmann::json::array()}};
    for (const char* step : {"register", "triangulation", "fusion", "local_ba", "culling", "total"}) {
      const std::string key = std::string("local_mapping.per_keyframe_ms.") + step;
      mapping["steps"].push_back(step);
      mapping["median"].push_back(rounded(f.number(key + ".median"), 1e-3));
      mapping["p95"].push_back(rounded(f.number(key + ".p95"), 1e-3));
    }
    mapping["keyframes_processed"] = f.find("local_mapping.keyframes_processed");
    mapping["keyframes"] = keyframe_times(f);
    out["mapping"] = std::move(mapping);
  } else {
    out["mapping"] = nullptr;
  }

  nlohmann::json strip_json = nlohmann::json::array();
  for (const auto& frame : embed_frames(run.saved_frames, strip)) {
    strip_json.push_back({{"frame", frame.frame_index}, {"src", frame.data_url}});
  }
  out["saved_frames"] = std::move(strip_json);
  out["saved_frames_total"] = run.saved_frames.size();
  return out;
}

nlohmann::json page_data(const std::vector<RunData>& runs, const FrameStripOptions& strip) {
  nlohmann::json doc;
  std::string title = "crowdslam report: ";
  for (size_t k = 0; k < runs.size(); ++k) title += (k > 0 ? " vs " : "") + runs[k].label;
  doc["title"] = title;
  doc["generated"] = utc_now("%Y-%m-%d %H:%M UTC");
  // Views follow the first run's ground truth, or its (unaligned) trajectory without one.
  io::Trajectory reference;
  if (!runs.empty()) {
    reference = ground_truth_in_span(runs.front());
    if (reference.empty()) {
      for (const auto& s : runs.front().segments)
        reference.insert(reference.end(), s.aligned.begin(), s.aligned.end());
    }
  }
  const ViewAxes axes = choose_view_axes(reference);
  doc["axes"] = {{"top", {axes.top[0], axes.top[1]}}, {"side", {axes.side[0], axes.side[1]}}};
  doc["summary_rows"] = summary_rows();
  nlohmann::json run_list = nlohmann::json::array();
  for (const auto& run : runs) run_list.push_back(run_page_data(run, strip));
  doc["runs"] = std::move(run_list);
  return doc;
}

}  // namespace crowdslam::report
