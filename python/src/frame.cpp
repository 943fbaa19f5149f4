#include "frame.h"

#include <pybind11/stl.h>

#include "arrays.h"

namespace py = pybind11;

namespace sluice::python {

namespace {

template <class T>
py::array_t<T> give(std::vector<T>&& values, std::vector<py::ssize_t> shape, ArrayPool* pool) {
  return pool ? pool->hand_over(std::move(values), std::move(shape)) : hand_over(std::move(values), std::move(shape));
}

}  // namespace

Frame make_frame(uint64_t index, io::ParticleArrays&& arrays, const std::vector<std::string>& names, bool timed,
                 ArrayPool* pool) {
  Frame f;
  f.index = index;
  if (timed) f.time = arrays.time;
  f.bytes_read = arrays.bytes_read;
  const auto n = py::ssize_t(arrays.count());
  f.positions = give(std::move(arrays.positions), {n, 3}, pool);
  f.lod = give(std::move(arrays.lod), {n}, pool);
  f.layer = give(std::move(arrays.layer), {n}, pool);
  for (size_t k = 0; k < names.size(); ++k) f.attributes[py::str(names[k])] = give(std::move(arrays.attributes[k]), {n}, pool);
  return f;
}

io::ParticleArrays spare_arrays(ArrayPool& pool, size_t attributes) {
  io::ParticleArrays a;
  a.positions = pool.take<float>();
  a.lod = pool.take<uint16_t>();
  a.layer = pool.take<uint8_t>();
  for (size_t k = 0; k < attributes; ++k) a.attributes.push_back(pool.take<float>());
  return a;
}

void bind_frame(py::module_& m) {
  py::class_<Frame>(m, "Frame", R"(One frame's particles as numpy arrays.

The arrays own their memory: they stay valid after the frame and its
sequence are gone. Particles are in the file's order (chunk by chunk), the
same order in every array.

Attributes:
    index: frame number in the file (0-based).
    time: simulation time in seconds, or None when the input stated no
        times (nor was a step given at conversion).
    positions: float32 array (N, 3), world units.
    lod: uint16 array (N,), each particle's stable LOD value (for blobs,
        the number of particles the blob stands for).
    layer: uint8 array (N,), the narrow-band layer of each particle:
        0 unclassified, 1 surface, 2 interior, 3 blob (see sluice.LAYERS).
    attributes: dict of name -> float32 array (N,), in the file's units.
    bytes_read: bytes of the file read for this frame (0 when streamed:
        the pipeline reads ahead).
)")
      .def_readonly("index", &Frame::index)
      .def_readonly("time", &Frame::time)
      .def_readonly("bytes_read", &Frame::bytes_read)
      .def_readonly("positions", &Frame::positions)
      .def_readonly("lod", &Frame::lod)
      .def_readonly("layer", &Frame::layer)
      .def_readonly("attributes", &Frame::attributes)
      .def("__len__", [](const Frame& f) { return f.lod.size(); }, "Number of particles.")
      .def("__getitem__", [](const Frame& f, const std::string& name) -> py::object {
             if (!f.attributes.contains(name)) {
               throw py::key_error("no attribute '" + name + "' in this frame (it has: " +
                                   py::str(py::list(f.attributes.attr("keys")())).cast<std::string>() + ")");
             }
             return f.attributes[py::str(name)];
           }, "An attribute's array by name, as frame['rho'].")
      .def("__repr__", [](const Frame& f) {
        const std::string when = f.time ? "t=" + py::str(py::float_(*f.time)).cast<std::string>() + " s" : "no time";
        return "<sluice.Frame " + std::to_string(f.index) + ": " + std::to_string(f.lod.size()) + " particles, " + when + ">";
      });
}

}  // namespace sluice::python
