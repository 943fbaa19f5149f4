// sluice.Renderer: a sequence's frames drawn offscreen into RGBA numpy
// images (a GPU, or lavapipe), through the same stream::Stream a host uses.
#pragma once

#include <pybind11/pybind11.h>

namespace sluice::python {

void bind_renderer(pybind11::module_& m);

}  // namespace sluice::python
