#pragma once
// What the report reads from one finished run: OUT/run.json, OUT/CameraTrajectory.txt,
// OUT/KeyFrameTrajectory.txt, OUT/frames/*.jpg and the dataset's ground truth (through io), with each
// map segment aligned to the ground truth exactly as run.json's accuracy was computed (eval::evaluate_ate:
// SE3, Sim3 for monocular; the longest segment is the one the summary reports).
//
// Bad input (run.json missing or unparsable, a key missing or of the wrong type, a trajectory file
// missing or malformed, poses that do not add up to the segments' counts) throws InputError naming the
// file and the key. A dataset that cannot be opened any more (moved, or run.json holds a path relative to
// another working directory) is not an error: the report is written without ground truth and says why.
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/eval/ate.h"
#include "crowdslam/io/dataset.h"
#include "crowdslam/io/trajectory.h"

namespace crowdslam::report {

// The per-frame record of run.json, column by column (one entry per frame).
struct FrameSeries {
  std::vector<double> index;
  std::vector<double> timestamp_s;
  std::vector<double> extraction_ms;
  std::vector<double> detector_wait_ms;
  std::vector<double> tracking_ms;
  std::vector<double> keypoints;  // kept by the people filter
  std::vector<double> keypoints_before_filter;
  std::vector<double> feature_budget;
  std::vector<double> people_area;  // fraction of the image
  std::vector<double> person_boxes;
  std::vector<double> tracked_points;
  std::vector<std::string> state;   // "ok", "lost", "bridged", "not_initialized"
  std::vector<std::string> method;  // "init", "motion", "reference", "relocalization", "lost", ""
  std::vector<bool> keyframe;
  [[nodiscard]] size_t size() const { return index.size(); }
};

// One map segment of the run (run.json "segments") with its poses and, when evaluated, its alignment.
struct SegmentTrajectory {
  int map_id = 0;
  io::Trajectory estimate;   // this segment's poses of CameraTrajectory.txt, as written
  io::Trajectory keyframes;  // this segment's poses of KeyFrameTrajectory.txt (empty when they do not add up)
  std::optional<eval::AteResult> ate;  // set when the segment could be evaluated
  io::Trajectory aligned;              // estimate in the ground-truth frame (== estimate when not evaluated)
  io::Trajectory aligned_keyframes;
  std::string error;  // why it was not evaluated ("" when it was, or without ground truth)
};

struct RunData {
  std::filesystem::path dir;
  std::string label;        // the directory's name
  nlohmann::json document;  // run.json as read
  io::SensorKind sensor = io::SensorKind::kRgbd;
  FrameSeries frames;
  io::Trajectory ground_truth;    // empty when none
  std::string ground_truth_note;  // why there is none ("" when there is)
  eval::Alignment alignment = eval::Alignment::kSe3;
  std::vector<SegmentTrajectory> segments;
  std::optional<size_t> evaluated_segment;          // index of the longest evaluated segment
  std::vector<std::filesystem::path> saved_frames;  // OUT/frames/*.jpg, sorted by name
  std::string keyframes_note;                       // why keyframes are not shown ("" when they are)
};

// Reads and checks everything; see the file comment for the errors.
RunData load_run(const std::filesystem::path& run_dir);

// The pieces of load_run, for tests.
//
// Parses run.json's "frames" into columns (InputError naming "frames[i].key").
FrameSeries read_frame_series(const nlohmann::json& document, const std::string& file);
// Splits `poses` (in file order) into consecutive parts of `counts` poses; throws InputError naming `file`
// when the counts do not add up to the number of poses.
std::vector<io::Trajectory> split_by_counts(const io::Trajectory& poses, const std::vector<size_t>& counts,
                                            const std::string& file, const std::string& what);
// As run.json's accuracy (run/run_document.cpp): every segment with at least 3 poses is aligned with
// eval::evaluate_ate; `ground_truth` empty: nothing is evaluated. Returns the index of the longest
// non-empty segment when it was evaluated.
std::optional<size_t> align_segments(const io::Trajectory& ground_truth, eval::Alignment alignment,
                                     std::vector<SegmentTrajectory>& segments);

}  // namespace crowdslam::report
