#pragma once
// `crowdslam run`: runs the system over a whole sequence and keeps its work on disk as it goes.
//
// Outputs in --out (README "Output files"):
//   OUT/run.json                written first with "end_state": "running"; rewritten at the end with the
//                               settings used, per-frame record, summary, map segments, accuracy, and how
//                               the run ended: "completed", "interrupted" or "failed: <reason>"
//   OUT/CameraTrajectory.txt    appended as frames are tracked (the journal), replaced at the end by the
//                               trajectory refined by bundle adjustment; every tracked frame of every map
//   OUT/KeyFrameTrajectory.txt  at the end: the keyframes of every map
//   OUT/frames/NNNNNN.jpg       with --save-frames N: every N-th frame, written as it is drawn
// --out is checked before anything is read and prepared before the first frame (journal/output_dir.h).
//
// How a run ends:
//   - completed: every frame read; exit 0 (or an InputError when it tracked no frame at all, unless
//     allow_untracked);
//   - interrupted (SIGINT/SIGTERM/SIGHUP inside util's InterruptScope): the loop stops at the next frame,
//     the threads stop at once (queued keyframes dropped, BA aborted), the outputs are written, and the
//     summary says so (exit 128 + signal in the app);
//   - failed: an error mid-sequence (e.g. an unreadable frame, a write error): what was tracked is
//     written with "failed: <reason>" and the error is rethrown (exit 1 in the app).
// Errors found before the first frame (settings, dataset, --out) leave nothing behind.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/io/dataset.h"
#include "crowdslam/system/run_observer.h"

namespace crowdslam::run {

struct RunOptions {
  std::string dataset;        // directory, video file or camera index
  std::string settings_path;  // empty: DATASET/settings.yaml
  std::string out_dir;
  bool overwrite = false;                // --overwrite: replace an earlier run in out_dir
  std::optional<io::SensorKind> sensor;  // override the sensor detected from the dataset
  bool sequential = false;
  size_t max_frames = 0;  // 0 = all
  bool progress = true;
  bool people_filter = true;         // --no-people-filter: static-world baseline (no filter, no FNU)
  std::string detections_file;       // --detections: MOT-format boxes instead of the network
  std::string detector_model;        // --detector: body | coco | PATH.cfg | PATH.onnx
  std::string filter_mode;           // --filter-mode: overrides PeopleFilter.mode (paper | depth)
  std::string detector_mode;         // --detector-mode: overrides Detector.mode (every_frame | latest)
  int detector_interval = 0;         // --detector-interval: overrides Detector.latest_interval (0 = keep)
  std::string box_tracker;           // --box-tracker: overrides Detector.tracker (on | off)
  std::string geometry;              // --geometry: overrides Geometry.dynamic_check (on | off)
  std::string ground;                // --ground: overrides Ground.enabled (on | off)
  size_t save_frames = 0;            // --save-frames N: every N-th frame drawn into OUT/frames/
  bool score_filter = false;  // --score-filter: the filter against DATASET/people_mask (filter_mask_score.h)
  std::string vocabulary;            // --vocabulary FILE | none ("" = the default vocabulary)
  bool loop_closing = true;          // --no-loop-closing
  int background_nice = 0;           // --background-nice: mapping and loop closing this much nicer (0-19)
  bool skip_bad_frames = false;      // --skip-bad-frames: an unreadable frame is counted and skipped
  bool allow_untracked = false;      // --allow-untracked: a run that tracks no frame is not an error
  size_t journal_flush_frames = 10;  // the trajectory journal is flushed every N tracked frames
  // --pace sensor: frames are replayed at their timestamps (as a live camera delivers them); a frame
  // whose successor has already arrived when tracking gets to it is dropped and counted, as a camera
  // driver drops frames nobody took. Default: every frame, as fast as the system goes.
  bool pace_sensor = false;
  // Saved maps (docs/MAPS.md): --load-map FILE.db before the first frame (relocalised into it), with
  // --localization tracking only (no keyframe or point created or removed); --save-map FILE.db at the
  // end, whatever the end state (an interrupted run's map is a valid map).
  std::string load_map;
  bool localization = false;
  std::string save_map;
  bool save_map_given = false;  // --save-map given (an empty path is then an error, not "no map")
  // --viewer: a live web viewer during the run (docs/VIEWER.md), on viewer_host:viewer_port (0: any
  // free port; the URL is printed).
  bool viewer = false;
  std::string viewer_host = "127.0.0.1";
  int viewer_port = 8080;
  double viewer_pause_timeout_s = 60;  // a pause with no page connected resumes after this (0: never)
  // Further observers of the run (called on the tracking thread, after the journal and the viewer; they
  // must outlive the call).
  std::vector<system::RunObserver*> observers;
};

// Accuracy of one trajectory (a map segment) against the ground truth.
struct SegmentAccuracy {
  int map_id = 0;
  size_t poses = 0;
  std::optional<double> ate_rmse_m;
  std::optional<double> rpe_trans_rmse_m;
  std::string error;  // why it could not be evaluated
};

struct RunSummary {
  system::EndState end;
  size_t frames = 0;
  size_t tracked = 0;  // == poses in CameraTrajectory.txt
  double tracked_percent = 0;
  size_t bridged = 0;  // frames with the motion model's pose while people hid the view (not tracked)
  std::optional<size_t> init_frame;  // index of the first frame that initialised a map
  size_t frames_localized_before_init =
      0;  // monocular: earlier frames the new maps localised (included in tracked)
  size_t frames_localized_after_reanchor = 0;  // monocular: lost frames a re-anchoring localised (in tracked)
  double throughput_fps = 0;
  double tracking_ms_median = 0;
  double tracking_ms_p95 = 0;
  double extraction_ms_median = 0;
  double total_ms_median = 0;
  double total_ms_p95 = 0;
  std::vector<system::MapSegment> segments;
  // Accuracy of the longest map segment (the only one unless the map was reset).
  std::optional<double> ate_rmse_m;
  std::optional<double> rpe_trans_rmse_m;
  std::optional<int> evaluated_map_id;
  std::vector<SegmentAccuracy> segment_accuracy;
  std::string out_dir;
  nlohmann::json json;  // the whole run.json document
};

// Runs the sequence. Returns the summary of a completed or interrupted run; throws InputError for bad
// input before the first frame (nothing written), and rethrows the error of a failed run after writing
// its outputs (the InputError's message then says where they are).
RunSummary run_sequence(const RunOptions& options);

}  // namespace crowdslam::run
