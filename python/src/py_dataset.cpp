// crowdslam.datasets: every input `crowdslam run --dataset` reads (io/dataset.h), frame by frame.
//
// Iterating decodes ahead on a background thread (run::FramePrefetcher, as the CLI does), so a Python
// loop that tracks each frame overlaps decoding with tracking exactly like `crowdslam run`.
#include <pybind11/stl.h>

#include <memory>

#include "crowdslam/run/frame_prefetcher.h"
#include "crowdslam/util/error.h"
#include "py_arrays.h"
#include "py_bindings.h"
#include "py_gil.h"

namespace crowdslam::python {

namespace {

constexpr size_t kPrefetchFrames = 3;  // as run_sequence

py::object optional_array(const cv::Mat& mat) { return mat.empty() ? py::object(py::none()) : py::object(mat_to_array(mat)); }
py::object optional_text(const std::string& text) { return text.empty() ? py::object(py::none()) : py::object(py::str(text)); }

class PySequence {
 public:
  PySequence(const std::string& spec, const io::DatasetOptions& options) {
    // Opening parses every list and checks that every image file exists.
    source_ = without_gil([&] { return io::open_source(spec, options); });
    dataset_ = dynamic_cast<io::Dataset*>(source_.get());
  }

  // A fresh pass from the first frame (datasets on disk); videos and cameras can be read once.
  size_t start() {
    return without_gil([this] {
      std::lock_guard lock(mutex_);
      prefetcher_.reset();  // joins the reader of an earlier pass
      if (started_ && !dataset_) {
        throw std::runtime_error(source_->path() + ": a " + source_->layout() +
                                 " can be iterated only once (it cannot rewind)");
      }
      if (dataset_) dataset_->rewind(0);
      started_ = true;
      prefetcher_ = std::make_unique<run::FramePrefetcher>(*source_, kPrefetchFrames);
      return ++generation_;
    });
  }

  std::optional<io::Frame> next(size_t generation) {
    return without_gil([&] {
      std::lock_guard lock(mutex_);
      if (generation != generation_ || !prefetcher_) {
        throw std::runtime_error(source_->path() + ": this iterator is stale (the sequence was iterated again)");
      }
      auto prefetched = prefetcher_->next();
      if (!prefetched) {
        prefetcher_.reset();
        return std::optional<io::Frame>();
      }
      return std::optional<io::Frame>(std::move(prefetched->frame));
    });
  }

  io::Frame at(py::ssize_t index) {
    if (!dataset_) throw py::type_error(source_->path() + ": a " + source_->layout() + " has no random access");
    const auto n = static_cast<py::ssize_t>(dataset_->size());
    if (index < 0) index += n;
    if (index < 0 || index >= n) {
      throw py::index_error("frame index " + std::to_string(index) + " out of range (" + std::to_string(n) + " frames)");
    }
    io::Frame frame;
    frame.info = dataset_->frame_info(static_cast<size_t>(index));
    frame.images = without_gil([&] { return dataset_->load(static_cast<size_t>(index)); });
    return frame;
  }

  [[nodiscard]] py::ssize_t length() const {
    const auto frames = source_->summary().frames;
    if (!frames) throw py::type_error(source_->path() + ": a camera has no length");
    return static_cast<py::ssize_t>(*frames);
  }

  [[nodiscard]] const io::FrameSource& source() const { return *source_; }
  [[nodiscard]] bool random_access() const { return dataset_ != nullptr; }

 private:
  std::unique_ptr<io::FrameSource> source_;
  io::Dataset* dataset_ = nullptr;  // source_ when it is a dataset on disk
  std::mutex mutex_;  // one pass at a time; next() from several threads is serialised
  std::unique_ptr<run::FramePrefetcher> prefetcher_;
  size_t generation_ = 0;
  bool started_ = false;
};

struct PyFrameIterator {
  py::object sequence;  // keeps the PySequence (and the source the prefetcher reads) alive
  size_t generation = 0;
};

py::dict summary_dict(const io::SourceSummary& s) {
  py::dict d;
  d["path"] = s.path;
  d["layout"] = s.layout;
  d["sensor"] = io::to_string(s.sensor);
  d["frames"] = s.frames ? py::object(py::int_(*s.frames)) : py::object(py::none());
  d["colour_entries"] = s.colour_entries;
  d["depth_entries"] = s.depth_entries;
  d["right_entries"] = s.right_entries;
  d["ground_truth_poses"] = s.ground_truth_poses;
  d["ground_truth_path"] = optional_text(s.ground_truth_path);
  d["first_timestamp"] = s.first_timestamp_s;
  d["last_timestamp"] = s.last_timestamp_s;
  d["fps"] = s.fps;
  d["settings_path"] = optional_text(s.settings_path);
  return d;
}

}  // namespace

void bind_datasets(py::module_& root) {
  py::module_ m = root.def_submodule("datasets", "Datasets, videos and cameras, as `crowdslam run --dataset` reads them.");

  py::class_<io::Frame>(m, "Frame", "One frame: images as stored (no copy) and its time stamp.")
      .def_property_readonly("index", [](const io::Frame& f) { return f.info.index; })
      .def_property_readonly("timestamp", [](const io::Frame& f) { return f.info.timestamp_s; }, "seconds")
      .def_property_readonly("image", [](const io::Frame& f) { return mat_to_array(f.images.colour); },
                             "uint8 (H, W, 3) BGR or (H, W) grey; the left image for stereo")
      .def_property_readonly("depth", [](const io::Frame& f) { return optional_array(f.images.depth); },
                             "uint16 (H, W) raw depth (Settings.depth_map_factor per metre), or None")
      .def_property_readonly("right", [](const io::Frame& f) { return optional_array(f.images.right); },
                             "uint8 right image (stereo), or None")
      .def_property_readonly("colour_path", [](const io::Frame& f) { return optional_text(f.info.colour_path); })
      .def_property_readonly("depth_path", [](const io::Frame& f) { return optional_text(f.info.depth_path); })
      .def_property_readonly("right_path", [](const io::Frame& f) { return optional_text(f.info.right_path); })
      .def("__repr__", [](const io::Frame& f) {
        return "<crowdslam.datasets.Frame " + std::to_string(f.info.index) + " t=" + std::to_string(f.info.timestamp_s) + ">";
      });

  py::class_<PyFrameIterator>(m, "FrameIterator")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](PyFrameIterator& it) {
        auto frame = it.sequence.cast<PySequence&>().next(it.generation);
        if (!frame) throw py::stop_iteration();
        return std::move(*frame);
      });

  py::class_<PySequence>(m, "Sequence",
                         "An opened dataset (TUM/Bonn, EuRoC, KITTI, image folder), video or camera. Iterating\n"
                         "yields Frames from the first one (decoded ahead on a thread); datasets on disk can be\n"
                         "iterated again and indexed.")
      .def("__iter__", [](py::object self) {
        const size_t generation = self.cast<PySequence&>().start();
        return PyFrameIterator{self, generation};
      })
      .def("__len__", &PySequence::length)
      .def("__getitem__", &PySequence::at, py::arg("index"))
      .def_property_readonly("path", [](const PySequence& s) { return s.source().path(); })
      .def_property_readonly("layout", [](const PySequence& s) { return s.source().layout(); },
                             "\"tum\", \"euroc\", \"kitti\", \"images\", \"video\" or \"camera\"")
      .def_property_readonly("sensor", [](const PySequence& s) { return io::to_string(s.source().sensor()); },
                             "the sensor detected from the layout: \"rgbd\", \"stereo\" or \"monocular\"")
      .def_property_readonly("ground_truth", [](const PySequence& s) { return trajectory_to_array(s.source().ground_truth()); },
                             "N x 8 TUM rows (timestamp tx ty tz qx qy qz qw), empty when there is none")
      .def_property_readonly("settings_path", [](const PySequence& s) { return optional_text(s.source().default_settings_path()); },
                             "DIR/settings.yaml when the dataset ships one, else None")
      .def_property_readonly("random_access", &PySequence::random_access)
      .def("summary", [](const PySequence& s) { return summary_dict(s.source().summary()); },
           "What `crowdslam dataset info` reports.");

  m.def(
      "open",
      [](const py::object& path, double fps, double max_time_difference) {
        io::DatasetOptions options;
        options.fps = fps;
        options.max_time_difference_s = max_time_difference;
        options.check();
        // A camera index may be given as an int, as cv2.VideoCapture takes it.
        const std::string spec = py::isinstance<py::int_>(path)
                                     ? std::to_string(path.cast<long long>())
                                     : py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
        return std::make_unique<PySequence>(spec, options);
      },
      py::arg("path"), py::kw_only(), py::arg("fps") = 0.0, py::arg("max_time_difference") = 0.02,
      "Opens a dataset directory (layout detected), a video file or a camera index (\"0\"). fps: frame\n"
      "rate for the time stamps of image folders and videos (0 = default); max_time_difference: TUM\n"
      "colour-depth association window in seconds. Raises crowdslam.InputError naming the file.");
}

}  // namespace crowdslam::python
