// The `sluice._core` extension: what `import sluice` exposes (python/sluice/
// __init__.py re-exports it). One file per part: frame.cpp (Frame),
// sequence.cpp (open, Sequence, streaming), convert.cpp (convert), export.cpp
// (export), renderer.cpp (Renderer), live_view.cpp (LiveView).
#include <pybind11/pybind11.h>

#include <string>

#include "convert.h"
#include "export.h"
#ifdef SLUICE_PYTHON_RENDER
#include "live_view.h"
#include "renderer.h"
#endif
#include "frame.h"
#include "sequence.h"
#include "sluice/error.h"
#include "sluice/import/convert.h"

namespace py = pybind11;

PYBIND11_MODULE(_core, m) {
  m.doc() = "sluice: huge particle-fluid sequences from disk, in numpy (see help(sluice.open), help(sluice.convert)).";
  static py::exception<sluice::Error> error(m, "Error", PyExc_RuntimeError);
  error.doc() = "What sluice could not do, with a message naming the file, frame and chunk where there is one.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const sluice::import::ConvertStopped& e) {
      const std::string kept = e.output_complete()
                                   ? "; the " + std::to_string(e.frames_kept()) + " frames before it are in " + e.output() +
                                         " (skip_bad=True leaves bad frames out)"
                                   : "; writing failed: " + e.output() + " holds what was written (`sluice recover` repairs it)";
      PyErr_SetString(error.ptr(), (std::string(e.what()) + kept).c_str());
    } catch (const sluice::Error& e) {
      PyErr_SetString(error.ptr(), e.what());
    }
  });
  m.attr("LAYERS") = py::make_tuple("all", "surface", "interior", "blobs");  // Frame.layer values, by index
  sluice::python::bind_frame(m);
  sluice::python::bind_sequence(m);
  sluice::python::bind_convert(m);
  sluice::python::bind_export(m);
#ifdef SLUICE_PYTHON_RENDER
  sluice::python::bind_renderer(m);
  sluice::python::bind_live_view(m);
#endif
}
