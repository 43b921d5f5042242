// crowdslam.Settings: the settings files `crowdslam run --settings` reads, as objects.
#include <pybind11/operators.h>
#include <pybind11/stl.h>

#include "crowdslam/io/settings.h"
#include "py_bindings.h"
#include "py_gil.h"

namespace crowdslam::python {

namespace {
std::string fspath(const py::object& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}
}  // namespace

io::SensorKind sensor_argument(const std::string& name, const std::string& what) {
  return io::parse_sensor_kind(name, what);
}

void bind_settings(py::module_& m) {
  py::class_<io::CameraSettings>(m, "CameraSettings", "Camera.* keys (pinhole, distortion, baseline, rate).")
      .def_readwrite("fx", &io::CameraSettings::fx)
      .def_readwrite("fy", &io::CameraSettings::fy)
      .def_readwrite("cx", &io::CameraSettings::cx)
      .def_readwrite("cy", &io::CameraSettings::cy)
      .def_readwrite("k1", &io::CameraSettings::k1)
      .def_readwrite("k2", &io::CameraSettings::k2)
      .def_readwrite("p1", &io::CameraSettings::p1)
      .def_readwrite("p2", &io::CameraSettings::p2)
      .def_readwrite("k3", &io::CameraSettings::k3)
      .def_readwrite("width", &io::CameraSettings::width, "0 = not given")
      .def_readwrite("height", &io::CameraSettings::height, "0 = not given")
      .def_readwrite("bf", &io::CameraSettings::bf, "baseline (m) * fx")
      .def_readwrite("fps", &io::CameraSettings::fps)
      .def_readwrite("rgb", &io::CameraSettings::rgb);
  py::class_<io::OrbSettings>(m, "OrbSettings", "ORBextractor.* keys.")
      .def_readwrite("n_features", &io::OrbSettings::n_features)
      .def_readwrite("scale_factor", &io::OrbSettings::scale_factor)
      .def_readwrite("n_levels", &io::OrbSettings::n_levels)
      .def_readwrite("ini_th_fast", &io::OrbSettings::ini_th_fast)
      .def_readwrite("min_th_fast", &io::OrbSettings::min_th_fast);
  py::class_<io::DetectorSettings>(m, "DetectorSettings", "Detector.* keys.")
      .def_readwrite("model_cfg", &io::DetectorSettings::model_cfg)
      .def_readwrite("model_weights", &io::DetectorSettings::model_weights)
      .def_readwrite("input_size", &io::DetectorSettings::input_size)
      .def_readwrite("confidence", &io::DetectorSettings::confidence)
      .def_readwrite("nms", &io::DetectorSettings::nms)
      .def_readwrite("person_class", &io::DetectorSettings::person_class)
      .def_readwrite("filter_before_nms", &io::DetectorSettings::filter_before_nms);
  py::class_<io::PeopleFilterSettings>(m, "PeopleFilterSettings", "PeopleFilter.* keys.")
      .def_readwrite("enabled", &io::PeopleFilterSettings::enabled)
      .def_readwrite("mode", &io::PeopleFilterSettings::mode)
      .def_readwrite("margin_px", &io::PeopleFilterSettings::margin_px)
      .def_readwrite("depth_margin_m", &io::PeopleFilterSettings::depth_margin_m)
      .def_readwrite("segment_from_m", &io::PeopleFilterSettings::segment_from_m)
      .def_readwrite("right_image", &io::PeopleFilterSettings::right_image);
  py::class_<io::FeatureBudgetSettings>(m, "FeatureBudgetSettings", "FeatureBudget.* keys.")
      .def_readwrite("enabled", &io::FeatureBudgetSettings::enabled)
      .def_readwrite("thresholds", &io::FeatureBudgetSettings::thresholds)
      .def_readwrite("factors", &io::FeatureBudgetSettings::factors)
      .def_readwrite("area", &io::FeatureBudgetSettings::area);
  py::class_<io::OutputSettings>(m, "OutputSettings", "Output.* keys.")
      .def_readwrite("trajectory_format", &io::OutputSettings::trajectory_format);

  py::class_<io::Settings>(m, "Settings",
                           "A settings file (ORB-SLAM2 format plus crowdslam's sections), README \"Settings\".")
      .def(py::init<>())
      .def_static(
          "load",
          [](const py::object& path, const std::string& sensor) {
            const std::string file = fspath(path);
            const io::SensorKind kind = sensor_argument(sensor, "Settings.load(): sensor");
            return without_gil([&] { return io::load_settings(file, kind); });
          },
          py::arg("path"), py::arg("sensor") = "rgbd",
          "Reads and checks a settings file for the sensor (keys only stereo / RGB-D need are enforced\n"
          "then). Raises crowdslam.InputError \"FILE: KEY: reason\" for a missing or invalid value.")
      .def(
          "save", [](const io::Settings& s, const py::object& path) { io::write_settings(fspath(path), s); },
          py::arg("path"), "Writes every key; Settings.load(path) gives an equal object back.")
      .def(
          "check", [](const io::Settings& s, const std::string& sensor) { s.check(sensor_argument(sensor, "check(): sensor")); },
          py::arg("sensor") = "rgbd", "Raises crowdslam.InputError naming the first invalid value.")
      .def_readonly("path", &io::Settings::path, "the file read")
      .def_readwrite("camera", &io::Settings::camera)
      .def_readwrite("th_depth", &io::Settings::th_depth)
      .def_readwrite("depth_map_factor", &io::Settings::depth_map_factor)
      .def_readwrite("orb", &io::Settings::orb)
      .def_property_readonly("has_rectification", [](const io::Settings& s) { return s.rectification.has_value(); })
      .def_readwrite("detector", &io::Settings::detector)
      .def_readwrite("people_filter", &io::Settings::people_filter)
      .def_readwrite("feature_budget", &io::Settings::feature_budget)
      .def_readwrite("output", &io::Settings::output)
      .def(py::self == py::self)  // NOLINT(misc-redundant-expression)
      .def("__repr__", [](const io::Settings& s) { return "<crowdslam.Settings " + s.path + ">"; });
}

}  // namespace crowdslam::python
