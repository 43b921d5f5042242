#pragma once
// Releasing the GIL around C++ work, safe at interpreter exit.
//
// pybind11's gil_scoped_release re-acquires the GIL in its destructor. When the interpreter is shutting
// down, a daemon thread that tries to re-acquire it is ended by Python with pthread_exit, i.e. a forced
// unwind; a forced unwind through a (noexcept) destructor calls std::terminate, and the process aborts
// instead of exiting 0. Unwinding would also drop Python references without the GIL. So the GIL is taken
// back here in ordinary code, and a thread that Python wants to end is parked instead: it holds no lock
// by then (the work and its locks are done), and the process exit ends it.
#include <pybind11/pybind11.h>

#include <chrono>
#include <cxxabi.h>
#include <exception>
#include <optional>
#include <thread>
#include <type_traits>
#include <utility>

namespace crowdslam::python {

namespace detail {

[[noreturn]] inline void park_forever() {
  for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

inline bool interpreter_finalizing() {
#if PY_VERSION_HEX >= 0x030D0000
  return Py_IsFinalizing() != 0;
#else
  return _Py_IsFinalizing() != 0;
#endif
}

inline void restore_or_park(PyThreadState* state) {
  if (interpreter_finalizing()) park_forever();
  try {
    PyEval_RestoreThread(state);
  } catch (abi::__forced_unwind&) {  // Python ending this (daemon) thread: see the header comment
    park_forever();
  }
}

}  // namespace detail

// Runs `work` (which must not touch Python objects) with the GIL released and returns its result;
// exceptions are rethrown with the GIL held again.
template <typename Work>
auto without_gil(Work&& work) -> decltype(work()) {
  using Result = decltype(work());
  std::exception_ptr error;
  PyThreadState* state = PyEval_SaveThread();
  if constexpr (std::is_void_v<Result>) {
    try {
      work();
    } catch (...) {
      error = std::current_exception();
    }
    detail::restore_or_park(state);
    if (error) std::rethrow_exception(error);
  } else {
    std::optional<Result> result;
    try {
      result.emplace(work());
    } catch (...) {
      error = std::current_exception();
    }
    detail::restore_or_park(state);
    if (error) std::rethrow_exception(error);
    return std::move(*result);
  }
}

}  // namespace crowdslam::python
