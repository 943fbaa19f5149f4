// A frame as Python sees it: numpy arrays over memory the frame hands over
// (positions N x 3 float32, LOD values, layers, one float32 array per
// attribute), its number and time.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sluice/io/particles.h"

namespace sluice::python {

struct Frame {
  uint64_t index = 0;
  std::optional<double> time;  // seconds; none when the input stated no times
  uint64_t bytes_read = 0;
  pybind11::array_t<float> positions;
  pybind11::array_t<uint16_t> lod;
  pybind11::array_t<uint8_t> layer;
  pybind11::dict attributes;  // name -> float32 array
};

class ArrayPool;

// Moves `arrays` into numpy (no copy). `names[i]` names arrays.attributes[i].
// With a pool, the arrays' memory goes back to it when they die. `timed`:
// the file states times (io::times_stated()); otherwise the frame has none.
Frame make_frame(uint64_t index, io::ParticleArrays&& arrays, const std::vector<std::string>& names, bool timed,
                 ArrayPool* pool = nullptr);
// Spare arrays from `pool` for the next frame of a stream.
io::ParticleArrays spare_arrays(ArrayPool& pool, size_t attributes);

void bind_frame(pybind11::module_& m);

}  // namespace sluice::python
