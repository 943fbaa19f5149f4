// A Python callable called from C++ work running without the GIL (on any
// thread): the call takes the GIL, Ctrl-C is checked after it, and an
// exception from either is saved and the C++ work unwound (PythonRaised),
// to be raised again on the calling thread once the work has stopped.
#pragma once

#include <pybind11/pybind11.h>

namespace sluice::python {

// Thrown through the C++ work when Python raised; caught by whoever
// started the work, who then calls PythonCallback::raise_saved().
struct PythonRaised {};

class PythonCallback {
 public:
  explicit PythonCallback(pybind11::object fn) : fn_(std::move(fn)) {}
  ~PythonCallback();
  PythonCallback(const PythonCallback&) = delete;
  PythonCallback& operator=(const PythonCallback&) = delete;

  // Calls the callable (if not None) with `argument`, then checks for
  // Ctrl-C. Takes the GIL. Throws PythonRaised.
  void operator()(const pybind11::object& argument);
  // Makes `argument` under the GIL, then calls (for arguments built from C++ values).
  template <class Make>
  void call_with(Make&& make) {
    pybind11::gil_scoped_acquire locked;
    call_locked(make());
  }
  // Raises the saved Python error, if any. GIL held.
  void raise_saved();

 private:
  void call_locked(const pybind11::object& argument);
  [[noreturn]] void save();

  pybind11::object fn_;
  pybind11::object type_, value_, trace_;
};

}  // namespace sluice::python
