#pragma once
// The parts of the crowdslam module, one function per binding file (module.cpp calls them in order).
#include <pybind11/pybind11.h>

#include <string>

#include "crowdslam/io/dataset.h"

namespace crowdslam::python {

namespace py = pybind11;

void bind_settings(py::module_& m);    // py_settings.cpp: Settings and its sections
void bind_system(py::module_& m);      // py_system_bind.cpp: System, FrameResult
void bind_datasets(py::module_& m);    // py_dataset.cpp: datasets.open, Sequence, Frame
void bind_eval(py::module_& m);        // py_eval.cpp: eval.ate, eval.rpe
void bind_detector(py::module_& m);    // py_detector.cpp: Detector

// "rgbd", "stereo", "mono"/"monocular"; InputError naming `what` otherwise.
io::SensorKind sensor_argument(const std::string& name, const std::string& what);

}  // namespace crowdslam::python
