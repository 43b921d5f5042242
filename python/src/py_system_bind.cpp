// Python signatures and docstrings of crowdslam.System and crowdslam.FrameResult.
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>

#include "py_arrays.h"
#include "py_gil.h"
#include "py_system.h"

namespace crowdslam::python {

namespace {

// The settings argument: a path (loaded for the sensor, as `crowdslam run --settings` does) or a
// crowdslam.Settings (checked for the sensor).
io::Settings settings_argument(const py::object& settings, io::SensorKind sensor) {
  if (py::isinstance<io::Settings>(settings)) {
    io::Settings s = settings.cast<io::Settings>();
    s.check(sensor);
    return s;
  }
  if (py::isinstance<py::str>(settings) || py::hasattr(settings, "__fspath__")) {
    const std::string path = py::str(py::module_::import("os").attr("fspath")(settings)).cast<std::string>();
    return without_gil([&] { return io::load_settings(path, sensor); });
  }
  throw py::type_error("System(): settings: expected a path (str or os.PathLike) or a crowdslam.Settings, got " +
                       describe(settings));
}

std::string optional_string(const std::optional<std::string>& value) { return value.value_or(""); }

std::unique_ptr<PySystem> make_system(const py::object& settings, const std::string& sensor,
                                      const std::optional<std::string>& vocabulary, bool people_filter,
                                      const std::optional<std::string>& detector,
                                      const std::optional<std::string>& detections, bool sequential,
                                      bool loop_closing, const std::optional<std::string>& filter_mode,
                                      bool record_keypoints, double max_wait_for_mapping_ms,
                                      bool replay_waits_for_mapping) {
  SystemArgs args;
  args.options.sensor = io::parse_sensor_kind(sensor, "System(): sensor");
  args.settings = settings_argument(settings, args.options.sensor);
  if (filter_mode) {
    if (*filter_mode != "paper" && *filter_mode != "depth") {
      throw py::value_error("System(): filter_mode: expected 'paper' or 'depth', got '" + *filter_mode + "'");
    }
    args.settings.people_filter.mode = *filter_mode;
  }
  if (!std::isfinite(max_wait_for_mapping_ms) || max_wait_for_mapping_ms < 0) {
    throw py::value_error("System(): max_wait_for_mapping_ms: expected a finite number >= 0, got " +
                          std::to_string(max_wait_for_mapping_ms));
  }
  args.options.vocabulary_path = optional_string(vocabulary);
  if (vocabulary && vocabulary->empty()) {
    throw py::value_error("System(): vocabulary: expected a file, \"none\" or None (the default vocabulary), got ''");
  }
  args.options.people_filter = people_filter;
  args.options.detector_model = optional_string(detector);
  args.options.detections_file = optional_string(detections);
  args.options.sequential = sequential;
  args.options.loop_closing = loop_closing;
  args.options.record_keypoints = record_keypoints;
  args.options.max_wait_for_mapping_ms = max_wait_for_mapping_ms;
  args.options.replay_waits_for_mapping = replay_waits_for_mapping;
  return std::make_unique<PySystem>(std::move(args));
}

const char* kSystemDoc = R"doc(A SLAM system: feed it frames with track(), read the trajectory and the map.

Arguments are those of `crowdslam run` (README "Running on your own data"):
  settings        settings file (ORB-SLAM2 format, e.g. config/Bonn.yaml) or a crowdslam.Settings
  sensor          "rgbd" (default), "stereo" or "mono"/"monocular"
  vocabulary      ORB vocabulary file; None = the default (vocabulary/crowdslam_orb.voc or
                  $CROWDSLAM_VOCABULARY); "none" = no place recognition
  people_filter   drop keypoints on people (the settings' PeopleFilter.enabled can turn it off too)
  detector        "body", "coco", a .cfg or .onnx path; None = the settings' Detector.model_cfg, else "body"
  detections      MOT-format boxes file used instead of the network (--detections)
  sequential      local mapping and loop closing inline after each frame: reproducible runs
  loop_closing    run the loop-closing thread (needs a vocabulary)
  filter_mode     "paper" or "depth"; None = the settings' PeopleFilter.mode
  record_keypoints  fill FrameResult.kept_keypoints / removed_keypoints
  max_wait_for_mapping_ms  how long tracking may wait for local mapping (threaded mode)
  replay_waits_for_mapping  mono: wait for every due keyframe (replays, as `crowdslam run`); False for a
                  live camera (as `--pace sensor`): only urgent keyframes are waited for

Use it as a context manager: `with crowdslam.System(...) as slam:` shuts it down at the end of the block;
the trajectory and map stay readable afterwards. Bad files raise crowdslam.InputError with the
message the CLI prints.)doc";

}  // namespace

void bind_system(py::module_& m) {
  py::class_<FrameResult>(m, "FrameResult", "What System.track() returns for one frame.")
      .def_property_readonly("index", [](const FrameResult& r) { return r.report.index; }, "0-based frame number")
      .def_property_readonly("timestamp", [](const FrameResult& r) { return r.report.timestamp_s; })
      .def_property_readonly("state", [](const FrameResult& r) { return std::string(tracking::to_string(r.report.state)); },
                             "\"ok\", \"lost\" or \"not_initialized\"")
      .def_property_readonly("ok", [](const FrameResult& r) { return r.report.state == tracking::TrackingState::kOk; })
      .def_property_readonly("method", [](const FrameResult& r) { return r.report.method; },
                             "how the pose was found: init, motion, reference, relocalization, lost")
      .def_property_readonly("pose", [](const FrameResult& r) { return optional_pose_to_array(r.world_from_cam); },
                             "4x4 float64 world_from_cam at tracking time, or None when not tracked")
      .def_property_readonly("tracked_points", [](const FrameResult& r) { return r.report.tracked_points; })
      .def_property_readonly("keypoints", [](const FrameResult& r) { return r.report.keypoints; },
                             "keypoints the frame kept (after the people filter)")
      .def_property_readonly("keypoints_before_filter", [](const FrameResult& r) { return r.report.keypoints_before_filter; })
      .def_property_readonly("keypoints_removed",
                             [](const FrameResult& r) { return std::max(0, r.report.keypoints_before_filter - r.report.keypoints); },
                             "keypoints the people filter dropped")
      .def_property_readonly("is_keyframe", [](const FrameResult& r) { return r.report.new_keyframe; })
      .def_property_readonly("feature_budget", [](const FrameResult& r) { return r.report.feature_budget; })
      .def_property_readonly("person_boxes", [](const FrameResult& r) { return boxes_to_array(r.report.boxes); },
                             "N x 4 float32 (x, y, width, height) pixels: the boxes the people filter used")
      .def_property_readonly("person_scores", [](const FrameResult& r) { return box_scores(r.report.boxes); })
      .def_property_readonly("num_people", [](const FrameResult& r) { return r.report.person_boxes; },
                             "people detected (boxes kept by non-maximum suppression)")
      .def_property_readonly("people_area", [](const FrameResult& r) { return r.report.people_area; },
                             "fraction of the image covered by people")
      .def_property_readonly("kept_keypoints", [](const FrameResult& r) { return keypoints_to_array(r.report.kept_keypoints); },
                             "N x 2 float32 pixel positions (only with record_keypoints=True)")
      .def_property_readonly("removed_keypoints", [](const FrameResult& r) { return keypoints_to_array(r.report.removed_keypoints); })
      .def_property_readonly("timings", [](const FrameResult& r) {
            const auto& p = r.report;
            py::dict t;
            t["extraction_ms"] = p.extraction_ms;
            t["tracking_ms"] = p.tracking_ms;
            t["detector_ms"] = p.detector_ms;
            t["detector_wait_ms"] = p.detector_wait_ms;
            t["waited_for_mapping_ms"] = p.waited_for_mapping_ms;
            t["total_ms"] = p.extraction_ms + p.detector_wait_ms + p.tracking_ms;
            return t;
          }, "milliseconds; total_ms = extraction + detector wait + tracking, as run.json")
      .def("__repr__", [](const FrameResult& r) {
        return "<FrameResult " + std::to_string(r.report.index) + " " + tracking::to_string(r.report.state) +
               ", " + std::to_string(r.report.tracked_points) + " tracked points>";
      });

  py::class_<PySystem>(m, "System", kSystemDoc)
      .def(py::init(&make_system), py::arg("settings"), py::arg("sensor") = "rgbd",
           py::arg("vocabulary") = py::none(), py::arg("people_filter") = true, py::arg("detector") = py::none(),
           py::arg("detections") = py::none(), py::arg("sequential") = false, py::arg("loop_closing") = true,
           py::arg("filter_mode") = py::none(), py::arg("record_keypoints") = false,
           py::arg("max_wait_for_mapping_ms") = 1000.0, py::arg("replay_waits_for_mapping") = true)
      .def("track", &PySystem::track, py::arg("image"), py::arg("depth") = py::none(), py::arg("right") = py::none(),
           py::kw_only(), py::arg("timestamp"),
           "Tracks one frame. image: uint8 (H, W, 3) BGR or (H, W) grey; depth (rgbd): uint16 raw units\n"
           "(DepthMapFactor per metre) or float32 metres; right (stereo): the right image. No copy is made\n"
           "of C-contiguous arrays. The GIL is released while the frame is processed.")
      .def("shutdown", &PySystem::shutdown,
           "Lets local mapping and loop closing finish their queues and stops them (idempotent). The\n"
           "trajectory, map and save_map() stay usable; track() raises afterwards.")
      .def("close", &PySystem::shutdown, "Same as shutdown().")
      .def_property_readonly("closed", &PySystem::closed)
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](PySystem& s, const py::object&, const py::object&, const py::object&) { s.shutdown(); })
      .def("trajectory", &PySystem::trajectory,
           "Every tracked frame (N x 8 float64: timestamp tx ty tz qx qy qz qw, world_from_cam), refined\n"
           "by bundle adjustment so far; CameraTrajectory.txt of `crowdslam run`.")
      .def("keyframe_trajectory", &PySystem::keyframe_trajectory, "The keyframes, N x 8 as trajectory().")
      .def("save_trajectory", &PySystem::save_trajectory, py::arg("path"), py::arg("format") = "",
           py::arg("keyframes") = false,
           "Writes trajectory() (or keyframe_trajectory()) with the CLI's writer: format 'tum', 'kitti',\n"
           "'euroc'; '' = the settings' Output.trajectory_format.")
      .def("_map_points", &PySystem::map_points)
      .def("_keyframes", &PySystem::keyframes)
      .def("load_map", &PySystem::load_map, py::arg("path"), py::arg("localization") = false,
           "Loads a saved map (before the first frame); localization=True never changes it. Returns what\n"
           "was loaded.")
      .def("save_map", &PySystem::save_map, py::arg("path"), py::arg("dataset") = "",
           "Saves the map (SQLite, docs/MAPS.md). Threaded mode: after shutdown().")
      .def("stats", &PySystem::stats, "Counts: tracked frames, keyframes, map points, resets, loops, segments.")
      .def_property_readonly("sensor", [](const PySystem& s) { return io::to_string(s.options().sensor); })
      .def_property_readonly("sequential", [](const PySystem& s) { return s.options().sequential; })
      .def_property_readonly("settings", [](const PySystem& s) { return s.settings(); }, "a copy of the settings used");

  m.def("_stop_all", &PySystem::stop_all, "atexit hook: stops the threads of every open System at once.");
}

}  // namespace crowdslam::python
