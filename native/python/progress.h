// The progress callback the library's long calls take, from a Python callable. Shared by the
// bindings of bake_transfer, face_sides and reference.
#pragma once

#include <pybind11/pybind11.h>

#include <cstddef>
#include <functional>

namespace sdpy {

namespace py = pybind11;

// The progress callback seen by the library: calls `progress` (when not None) with the GIL held (None
// or any true value continues, a false value cancels) and checks for signals (Ctrl-C cancels the bake with KeyboardInterrupt). A Python exception propagates
// as py::error_already_set, which cancels the bake and is re-raised.
inline std::function<bool(std::size_t, std::size_t)> progress_function(const py::object* progress) {
  return [progress](std::size_t done, std::size_t total) -> bool {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (progress->is_none()) return true;
    const py::object answer = (*progress)(done, total);
    if (answer.is_none()) return true;
    const int truth = PyObject_IsTrue(answer.ptr());
    if (truth < 0) throw py::error_already_set();
    return truth != 0;
  };
}

}  // namespace sdpy
