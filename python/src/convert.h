// sluice.convert(input, output, ...): import::convert with a progress
// callback, Ctrl-C honoured between frames.
#pragma once

#include <pybind11/pybind11.h>

namespace sluice::python {

void bind_convert(pybind11::module_& m);

}  // namespace sluice::python
