// sluice.LiveView: frames a running simulation pushes from numpy, drawn as
// liquid in a window (or offscreen) on a thread of its own, optionally
// recorded to a .sluice file.
//
// push() copies the arrays (the simulation may change them at once) into a
// one-frame mailbox and returns: a frame the view has not taken when the
// next arrives is dropped and counted, unless the view was made to wait
// (keep_all), so a slow view never slows the simulation. Frames the view
// takes are drawn and, with a recording, appended to it; dropped frames
// are neither.
#pragma once

#include <pybind11/pybind11.h>

namespace sluice::python {

void bind_live_view(pybind11::module_& m);

}  // namespace sluice::python
