// The crowdslam Python module (crowdslam._core; the package in python/crowdslam/ wraps it). It binds the
// library API the CLI uses (docs/PYTHON.md); nothing here changes what the library does.
#include <pybind11/pybind11.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "crowdslam/util/error.h"
#include "crowdslam/util/version.h"
#include "py_bindings.h"

namespace py = pybind11;

PYBIND11_MODULE(_core, m) {
  using namespace crowdslam::python;
  m.doc() = "crowdslam: visual SLAM for crowded places (native part; import crowdslam instead)";
  m.attr("__version__") = crowdslam::version();
  m.attr("__git_commit__") = crowdslam::git_commit();

  // Every user-input error of the library (files, settings, arguments) arrives as one exception type with
  // the message the CLI would print. A ValueError, so `except ValueError` catches bad input generally.
  py::register_exception<crowdslam::InputError>(m, "InputError", PyExc_ValueError);

  m.def(
      "set_log_level",
      [](const std::string& level) {
        const auto parsed = spdlog::level::from_str(level);
        // from_str maps anything unknown to "off": only accept the names it knows.
        if (parsed == spdlog::level::off && level != "off") {
          throw py::value_error("set_log_level(): level: expected trace, debug, info, warning, error, critical or "
                                "off, got '" + level + "'");
        }
        spdlog::set_level(parsed);
      },
      py::arg("level"),
      "The library's log level (messages go to stderr, as the CLI's): 'debug', 'info', 'warning' (the\n"
      "module's default: research code and notebooks want warnings, not progress lines), 'error', 'off'.");

  // As the CLI: log lines on stderr. Only warnings by default (the CLI's --quiet).
  if (!spdlog::get("crowdslam")) spdlog::set_default_logger(spdlog::stderr_color_mt("crowdslam"));
  spdlog::set_level(spdlog::level::warn);

  bind_settings(m);
  bind_system(m);
  bind_datasets(m);
  bind_eval(m);
  bind_detector(m);
}
