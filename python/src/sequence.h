// sluice.open(path) -> a Sequence: the file's description, random access to
// its frames and streaming through the prefetch pipeline.
#pragma once

#include <pybind11/pybind11.h>

namespace sluice::python {

void bind_sequence(pybind11::module_& m);

}  // namespace sluice::python
