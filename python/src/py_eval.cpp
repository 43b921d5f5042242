// crowdslam.eval: the accuracy metrics of `crowdslam eval ate|rpe` (eval/ate.h, eval/rpe.h), on arrays
// or trajectory files, with the same numbers.
#include <pybind11/stl.h>

#include "crowdslam/eval/ate.h"
#include "crowdslam/eval/rpe.h"
#include "py_arrays.h"
#include "py_bindings.h"
#include "py_gil.h"

namespace crowdslam::python {

namespace {

struct TrajectoryArgument {
  io::Trajectory trajectory;
  std::string name;  // file path, or the argument name for arrays (used in error messages)
};

// A file (TUM, KITTI or EuRoC, detected as `crowdslam eval` does) or an N x 8 TUM array.
TrajectoryArgument trajectory_argument(const py::object& value, const std::string& call, const std::string& name) {
  TrajectoryArgument out;
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")) {
    out.name = py::str(py::module_::import("os").attr("fspath")(value)).cast<std::string>();
    out.trajectory = without_gil([&] { return io::read_trajectory(out.name); });  // reading and parsing a file
    return out;
  }
  if (!py::isinstance<py::array>(value)) {
    throw py::type_error(call + ": " + name + ": expected a trajectory file path or an N x 8 float64 array " +
                         "(timestamp tx ty tz qx qy qz qw), got " + describe(value));
  }
  out.name = name;
  out.trajectory = trajectory_from_array(value, call + ": " + name);
  return out;
}

py::dict stats_dict(const eval::ErrorStats& s) {
  py::dict d;
  d["rmse"] = s.rmse;
  d["mean"] = s.mean;
  d["median"] = s.median;
  d["std"] = s.std;
  d["min"] = s.min;
  d["max"] = s.max;
  return d;
}

py::array_t<double> matrix_array(const geometry::Mat3& r) {
  std::vector<double> values;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) values.push_back(r(i, j));
  }
  return vector_to_array(std::move(values), {3, 3});
}

}  // namespace

void bind_eval(py::module_& root) {
  py::module_ m = root.def_submodule("eval", "Trajectory accuracy as `crowdslam eval` (TUM benchmark metrics).");

  py::class_<eval::ErrorStats>(m, "ErrorStats", "Statistics of a list of errors, as TUM's scripts print them.")
      .def_readonly("count", &eval::ErrorStats::count)
      .def_readonly("rmse", &eval::ErrorStats::rmse)
      .def_readonly("mean", &eval::ErrorStats::mean)
      .def_readonly("median", &eval::ErrorStats::median)
      .def_readonly("std", &eval::ErrorStats::std, "population standard deviation")
      .def_readonly("min", &eval::ErrorStats::min)
      .def_readonly("max", &eval::ErrorStats::max)
      .def("as_dict", &stats_dict)
      .def("__repr__", [](const eval::ErrorStats& s) {
        return "<ErrorStats rmse=" + std::to_string(s.rmse) + " n=" + std::to_string(s.count) + ">";
      });

  py::class_<eval::AteResult>(m, "AteResult", "Absolute trajectory error (`crowdslam eval ate`).")
      .def_readonly("translation_error", &eval::AteResult::translation_error_m, "metres")
      .def_property_readonly("rmse", [](const eval::AteResult& r) { return r.translation_error_m.rmse; },
                             "translation RMSE in metres")
      .def_property_readonly("compared_pose_pairs", [](const eval::AteResult& r) { return r.matches.size(); })
      .def_readonly("ground_truth_poses", &eval::AteResult::ground_truth_poses)
      .def_readonly("estimate_poses", &eval::AteResult::estimate_poses)
      .def_property_readonly("errors", [](const eval::AteResult& r) {
        std::vector<double> e = r.errors_m;
        const auto n = static_cast<py::ssize_t>(e.size());
        return vector_to_array(std::move(e), {n});
      }, "per matched pose, metres")
      .def_property_readonly("rotation", [](const eval::AteResult& r) { return matrix_array(r.alignment.rotation); })
      .def_property_readonly("translation", [](const eval::AteResult& r) {
        const auto& t = r.alignment.translation;
        return vector_to_array(std::vector<double>{t.x(), t.y(), t.z()}, {3});
      })
      .def_property_readonly("scale", [](const eval::AteResult& r) { return r.alignment.scale; },
                             "gt = scale * rotation @ est + translation")
      .def("__repr__", [](const eval::AteResult& r) {
        return "<AteResult rmse=" + std::to_string(r.translation_error_m.rmse) + " m, " +
               std::to_string(r.matches.size()) + " pairs>";
      });

  py::class_<eval::RpeResult>(m, "RpeResult", "Relative pose error (`crowdslam eval rpe`).")
      .def_readonly("translation_error", &eval::RpeResult::translation_error_m, "metres")
      .def_readonly("rotation_error", &eval::RpeResult::rotation_error_deg, "degrees")
      .def_property_readonly("rmse", [](const eval::RpeResult& r) { return r.translation_error_m.rmse; })
      .def_property_readonly("compared_pose_pairs", [](const eval::RpeResult& r) { return r.pairs.size(); })
      .def_readonly("ground_truth_max_time_difference", &eval::RpeResult::ground_truth_max_time_difference_s)
      .def("__repr__", [](const eval::RpeResult& r) {
        return "<RpeResult rmse=" + std::to_string(r.translation_error_m.rmse) + " m, " +
               std::to_string(r.pairs.size()) + " pairs>";
      });

  m.def(
      "ate",
      [](const py::object& ground_truth, const py::object& estimate, const std::string& align, double max_diff,
         double offset, double scale) {
        eval::AteOptions options;
        options.alignment = eval::parse_alignment(align);
        options.max_difference_s = max_diff;
        options.offset_s = offset;
        options.scale = scale;
        options.check();
        const auto gt = trajectory_argument(ground_truth, "ate()", "ground_truth");
        const auto est = trajectory_argument(estimate, "ate()", "estimate");
        return without_gil([&] { return eval::evaluate_ate(gt.trajectory, est.trajectory, options, gt.name, est.name); });
      },
      py::arg("ground_truth"), py::arg("estimate"), py::arg("align") = "se3", py::arg("max_diff") = 0.02,
      py::arg("offset") = 0.0, py::arg("scale") = 1.0,
      "Absolute trajectory error, exactly as `crowdslam eval ate` (TUM evaluate_ate.py). Trajectories are\n"
      "files (TUM, KITTI, EuRoC) or N x 8 arrays (timestamp tx ty tz qx qy qz qw). align: 'se3', 'sim3'\n"
      "(monocular) or 'none'; max_diff: association window (s); offset: added to the estimate's stamps;\n"
      "scale: applied to the estimate's positions.");

  m.def(
      "rpe",
      [](const py::object& ground_truth, const py::object& estimate, double delta, const std::string& delta_unit,
         double offset, double scale) {
        eval::RpeOptions options;
        options.delta = delta;
        options.delta_unit = eval::parse_delta_unit(delta_unit);
        options.offset_s = offset;
        options.scale = scale;
        options.check();
        const auto gt = trajectory_argument(ground_truth, "rpe()", "ground_truth");
        const auto est = trajectory_argument(estimate, "rpe()", "estimate");
        return without_gil([&] { return eval::evaluate_rpe(gt.trajectory, est.trajectory, options, gt.name, est.name); });
      },
      py::arg("ground_truth"), py::arg("estimate"), py::arg("delta") = 1.0, py::arg("delta_unit") = "s",
      py::arg("offset") = 0.0, py::arg("scale") = 1.0,
      "Relative pose error, exactly as `crowdslam eval rpe` (TUM evaluate_rpe.py --fixed_delta): pairs\n"
      "`delta` apart in delta_unit 's' or 'frames'.");
}

}  // namespace crowdslam::python
