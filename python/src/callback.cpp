#include "callback.h"

namespace py = pybind11;

namespace sluice::python {

PythonCallback::~PythonCallback() {
  py::gil_scoped_acquire locked;
  type_ = value_ = trace_ = fn_ = py::object();
}

void PythonCallback::operator()(const py::object& argument) {
  py::gil_scoped_acquire locked;
  call_locked(argument);
}

void PythonCallback::call_locked(const py::object& argument) {
  if (!fn_.is_none()) {
    try {
      fn_(argument);
    } catch (py::error_already_set& e) {
      e.restore();
      save();
    }
  }
  if (PyErr_CheckSignals() != 0) save();
}

void PythonCallback::save() {
  PyObject *type = nullptr, *value = nullptr, *trace = nullptr;
  PyErr_Fetch(&type, &value, &trace);
  type_ = py::reinterpret_steal<py::object>(type);
  value_ = py::reinterpret_steal<py::object>(value);
  trace_ = py::reinterpret_steal<py::object>(trace);
  throw PythonRaised{};
}

void PythonCallback::raise_saved() {
  if (!type_) return;
  PyErr_Restore(type_.release().ptr(), value_.release().ptr(), trace_.release().ptr());
  throw py::error_already_set();
}

}  // namespace sluice::python
