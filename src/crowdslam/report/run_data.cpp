#include "crowdslam/report/run_data.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <fstream>
#include <set>

#include "crowdslam/io/dataset.h"
#include "crowdslam/report/json_fields.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::report {

namespace fs = std::filesystem;

namespace {

nlohmann::json read_document(const fs::path& path) {
  const std::string name = clip_text(path.string());
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw input_error(name, "not found (is the directory the --out of a crowdslam run?)");
  }
  std::ifstream in(path);
  if (!in) throw input_error(name, "cannot be read");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw input_error(name, std::string("not valid JSON: ") + e.what());
  }
}

// Stamps of the tracked frames, for a KITTI trajectory (no stamps in the file): frames tracked "ok" and
// each segment's first tracked stamp (a monocular map's first keyframe is an earlier frame).
std::vector<double> tracked_stamps(const FrameSeries& frames, const nlohmann::json& segments) {
  std::set<double> stamps;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames.state[i] == "ok") stamps.insert(frames.timestamp_s[i]);
  }
  for (const auto& s : segments) {
    if (s.contains("first_stamp") && s["first_stamp"].is_number())
      stamps.insert(s["first_stamp"].get<double>());
  }
  return {stamps.begin(), stamps.end()};
}

io::Trajectory read_poses(const fs::path& path, const std::vector<double>& kitti_stamps) {
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw input_error(clip_text(name), "not found");
  if (io::detect_trajectory_format(name) == io::TrajectoryFormat::kKitti) {
    return io::read_kitti_trajectory(name, kitti_stamps);
  }
  return io::read_trajectory(name);
}

// The ground truth of the run's dataset, or empty with `note` saying why.
io::Trajectory read_ground_truth(const std::string& dataset, std::string& note) {
  std::error_code ec;
  if (!fs::is_directory(dataset, ec)) {
    note = "dataset " + clip_text(dataset) + " is not a directory here (moved, a video or a camera?)";
    return {};
  }
  try {
    auto source = io::open_dataset(dataset);
    io::Trajectory ground_truth = source->ground_truth();
    if (ground_truth.empty()) note = "dataset " + clip_text(dataset) + " has no ground truth";
    return ground_truth;
  } catch (const InputError& e) {
    note = std::string("ground truth not read: ") + e.what();
    return {};
  }
}

std::vector<fs::path> list_saved_frames(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_regular_file(ec) && entry.path().extension() == ".jpg") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

FrameSeries read_frame_series(const nlohmann::json& document, const std::string& file) {
  const JsonFields fields(document, file);
  const auto& frames = fields.array("frames");
  FrameSeries s;
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    const std::string where = "frames[" + std::to_string(i) + "]";
    s.index.push_back(fields.number_in(f, where, "index"));
    s.timestamp_s.push_back(fields.number_in(f, where, "timestamp"));
    s.extraction_ms.push_back(fields.number_in(f, where, "extraction_ms"));
    s.detector_wait_ms.push_back(fields.number_in(f, where, "detector_wait_ms"));
    s.tracking_ms.push_back(fields.number_in(f, where, "tracking_ms"));
    s.keypoints.push_back(fields.number_in(f, where, "keypoints"));
    s.keypoints_before_filter.push_back(fields.number_in(f, where, "keypoints_before_filter"));
    s.feature_budget.push_back(fields.number_in(f, where, "feature_budget"));
    s.people_area.push_back(fields.number_in(f, where, "people_area"));
    s.person_boxes.push_back(fields.number_in(f, where, "person_boxes"));
    s.tracked_points.push_back(fields.number_in(f, where, "tracked_points"));
    s.state.push_back(fields.text_in(f, where, "state"));
    s.method.push_back(fields.text_in(f, where, "method"));
    const auto it = f.find("keyframe");
    if (it == f.end() || !it->is_boolean()) fields.fail(where + ".keyframe", "missing or not true/false");
    s.keyframe.push_back(it->get<bool>());
  }
  return s;
}

std::vector<io::Trajectory> split_by_counts(const io::Trajectory& poses, const std::vector<size_t>& counts,
                                            const std::string& file, const std::string& what) {
  size_t total = 0;
  for (const size_t c : counts) total += c;
  if (total != poses.size()) {
    throw input_error(file, std::to_string(poses.size()) + " poses, but run.json's segments give " +
                                std::to_string(total) + " " + what + " (is the file from another run?)");
  }
  std::vector<io::Trajectory> parts;
  size_t start = 0;
  for (const size_t c : counts) {
    parts.emplace_back(poses.begin() + static_cast<std::ptrdiff_t>(start),
                       poses.begin() + static_cast<std::ptrdiff_t>(start + c));
    start += c;
  }
  return parts;
}

std::optional<size_t> align_segments(const io::Trajectory& ground_truth, eval::Alignment alignment,
                                     std::vector<SegmentTrajectory>& segments) {
  std::optional<size_t> longest;
  for (size_t k = 0; k < segments.size(); ++k) {
    auto& s = segments[k];
    s.aligned = s.estimate;
    s.aligned_keyframes = s.keyframes;
    if (s.estimate.empty()) continue;
    if (!longest || s.estimate.size() > segments[*longest].estimate.size()) longest = k;
    if (ground_truth.empty()) continue;
    if (s.estimate.size() < 3) {
      s.error = "fewer than 3 poses";
      continue;
    }
    eval::AteOptions options;  // the defaults run.json's accuracy uses
    options.alignment = alignment;
    try {
      s.ate = eval::evaluate_ate(ground_truth, s.estimate, options, "ground truth",
                                 "CameraTrajectory.txt (map " + std::to_string(s.map_id) + ")");
      s.aligned = eval::apply_alignment(s.estimate, s.ate->alignment, options.scale);
      s.aligned_keyframes = eval::apply_alignment(s.keyframes, s.ate->alignment, options.scale);
    } catch (const InputError& e) {
      s.error = e.what();
    }
  }
  if (longest && segments[*longest].ate) return longest;
  return std::nullopt;
}

RunData load_run(const fs::path& run_dir) {
  RunData run;
  run.dir = run_dir;
  run.label = fs::absolute(run_dir).lexically_normal().filename().string();
  if (run.label.empty())
    run.label = fs::absolute(run_dir).lexically_normal().parent_path().filename().string();
  const fs::path json_path = run_dir / "run.json";
  const std::string json_name = clip_text(json_path.string());
  run.document = read_document(json_path);
  const JsonFields fields(run.document, json_name);
  if (!run.document.is_object()) fields.fail("(document)", "expected an object");
  const std::string end_state = fields.text("end_state");
  if (end_state == "running") {
    throw input_error(json_name,
                      "key 'end_state' is \"running\": the run has not finished (or was killed); "
                      "there is no summary to report");
  }
  for (const char* key : {"summary.frames", "summary.tracked_frames", "summary.tracked_percent",
                          "summary.throughput_fps", "summary.total_ms_median", "summary.total_ms_p95",
                          "summary.keyframes", "summary.map_points", "summary.map_resets"}) {
    (void)fields.number(key);
  }
  run.sensor = io::parse_sensor_kind(fields.text("sensor"), json_name + ": key 'sensor'");
  const std::string dataset = fields.text("dataset");
  run.frames = read_frame_series(run.document, json_name);

  const auto& segments = fields.array("segments");
  std::vector<size_t> pose_counts, keyframe_counts;
  std::vector<int> map_ids;
  for (size_t k = 0; k < segments.size(); ++k) {
    const std::string where = "segments[" + std::to_string(k) + "]";
    map_ids.push_back(static_cast<int>(fields.number_in(segments[k], where, "map_id")));
    pose_counts.push_back(static_cast<size_t>(fields.number_in(segments[k], where, "tracked")));
    keyframe_counts.push_back(static_cast<size_t>(fields.number_in(segments[k], where, "keyframes")));
  }
  const auto stamps = tracked_stamps(run.frames, segments);
  const fs::path camera_path = run_dir / "CameraTrajectory.txt";
  const auto poses = split_by_counts(read_poses(camera_path, stamps), pose_counts,
                                     clip_text(camera_path.string()), "tracked frames");
  // Keyframes are shown, not evaluated: a file that does not add up is left out with a note.
  std::vector<io::Trajectory> keyframes(segments.size());
  const fs::path keyframe_path = run_dir / "KeyFrameTrajectory.txt";
  try {
    keyframes = split_by_counts(read_poses(keyframe_path, {}), keyframe_counts,
                                clip_text(keyframe_path.string()), "keyframes");
  } catch (const InputError& e) {
    run.keyframes_note = e.what();
    spdlog::warn("report: keyframes not shown: {}", e.what());
  }
  for (size_t k = 0; k < segments.size(); ++k) {
    SegmentTrajectory s;
    s.map_id = map_ids[k];
    s.estimate = poses[k];
    s.keyframes = keyframes[k];
    run.segments.push_back(std::move(s));
  }

  // The alignment run.json's accuracy used (Sim3 for monocular, else SE3).
  const auto& recorded = fields.find("accuracy.alignment");
  run.alignment = recorded.is_string() ? eval::parse_alignment(recorded.get<std::string>())
                                       : (run.sensor == io::SensorKind::kMonocular ? eval::Alignment::kSim3
                                                                                   : eval::Alignment::kSe3);
  run.ground_truth = read_ground_truth(dataset, run.ground_truth_note);
  if (!run.ground_truth_note.empty())
    spdlog::warn("report: {}: no ground truth: {}", run.label, run.ground_truth_note);
  run.evaluated_segment = align_segments(run.ground_truth, run.alignment, run.segments);
  run.saved_frames = list_saved_frames(run_dir / "frames");
  return run;
}

}  // namespace crowdslam::report
