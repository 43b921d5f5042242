// crowdslam.Detector: the person detector the people filter uses (people/darknet_detector.h), on its own.
#include <pybind11/stl.h>

#include <mutex>

#include "crowdslam/io/settings.h"
#include "crowdslam/people/darknet_detector.h"
#include "crowdslam/people/detector_setup.h"
#include "crowdslam/people/model_paths.h"
#include "py_arrays.h"
#include "py_bindings.h"
#include "py_gil.h"

namespace crowdslam::python {

namespace {

class PyDetector {
 public:
  // As `crowdslam detect`: the settings' Detector.* keys first, then the arguments that were given.
  PyDetector(const std::optional<std::string>& model, const std::optional<std::string>& settings,
             std::optional<int> input_size, std::optional<double> confidence, std::optional<double> nms,
             std::optional<int> person_class) {
    // The model and options as `crowdslam run` and `crowdslam detect` build them (people/detector_setup.h):
    // `model` first, else the settings' Detector.model_cfg (a zoo name or a path), else "body".
    io::DetectorSettings d;
    if (settings) d = io::load_settings(*settings, io::SensorKind::kMonocular).detector;
    people::DetectorSetup setup = people::detector_setup(d, model.value_or(""));
    people::ModelFiles files = std::move(setup.model);
    people::DetectorOptions options = setup.options;
    if (input_size) {  // square, over the settings' WIDTHxHEIGHT
      options.input_size = *input_size;
      options.input_width = options.input_height = 0;
    }
    if (confidence) options.confidence = *confidence;
    if (nms) options.nms = *nms;
    if (person_class) files.person_class = options.person_class = *person_class;
    options.check();
    // Loads the network and runs a warm-up forward pass.
    detector_ = without_gil([&] { return std::make_unique<people::DarknetDetector>(files, options); });
  }

  py::tuple detect(const py::object& image, bool raw) {
    py::object keep;
    const cv::Mat mat = image_from_array(image, "detect(): image", keep);
    const people::Detections detections = without_gil([&] {
      std::lock_guard lock(mutex_);  // one forward pass at a time: a cv::dnn::Net is not thread-safe
      return detector_->detect(mat, frame_index_++);
    });
    const auto& boxes = raw ? detections.raw : detections.boxes;
    last_time_ms_ = detections.time_ms;
    return py::make_tuple(boxes_to_array(boxes), box_scores(boxes));
  }

  [[nodiscard]] std::string name() const { return detector_->name(); }
  [[nodiscard]] double last_time_ms() const { return last_time_ms_; }

 private:
  std::unique_ptr<people::DarknetDetector> detector_;
  std::mutex mutex_;
  size_t frame_index_ = 0;
  double last_time_ms_ = 0;
};

}  // namespace

void bind_detector(py::module_& m) {
  py::class_<PyDetector>(m, "Detector",
                         "The people filter's person detector (OpenCV DNN on the CPU): Yolo-Fastest \"body\"\n"
                         "(default) or \"coco\" from models/, or a Darknet .cfg (+ .weights beside it) / .onnx.\n"
                         "settings: a settings file whose Detector.* keys are used; explicit arguments win.")
      .def(py::init<const std::optional<std::string>&, const std::optional<std::string>&, std::optional<int>,
                    std::optional<double>, std::optional<double>, std::optional<int>>(),
           py::arg("model") = py::none(), py::kw_only(), py::arg("settings") = py::none(),
           py::arg("input_size") = py::none(), py::arg("confidence") = py::none(), py::arg("nms") = py::none(),
           py::arg("person_class") = py::none())
      .def("detect", &PyDetector::detect, py::arg("image"), py::arg("raw") = false,
           "People in a uint8 BGR (H, W, 3) or grey (H, W) image: (boxes N x 4 float32 x, y, width,\n"
           "height in pixels; scores N float32), by decreasing score. raw=True: every box above the\n"
           "confidence threshold before non-maximum suppression. The GIL is released meanwhile.")
      .def_property_readonly("name", &PyDetector::name)
      .def_property_readonly("last_time_ms", &PyDetector::last_time_ms, "forward time of the last detect()");
}

}  // namespace crowdslam::python
