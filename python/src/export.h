// sluice.export(seq, output, ...): io::export_series with a progress
// callback, Ctrl-C honoured between frames.
#pragma once

#include <pybind11/pybind11.h>

namespace sluice::python {

void bind_export(pybind11::module_& m);

}  // namespace sluice::python
