// sluice.convert(input, output, ...): import::convert with a progress
// callback, Ctrl-C honoured between frames.
#pragma once

#include <pybind11/pybind11.h>

#include "sluice/import/convert.h"

namespace sluice::python {

// A conversion's progress as the dict progress callbacks get
// (frames_done, frames, input_bytes, output_bytes). GIL held.
pybind11::dict progress_dict(const import::ConvertProgress& p);

void bind_convert(pybind11::module_& m);

}  // namespace sluice::python
