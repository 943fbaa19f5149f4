// Hands C++ vectors to numpy without copying: the array's base is a
// capsule owning the vector, so the array keeps its memory alive after the
// sequence or frame it came from is gone.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <vector>

namespace sluice::python {

template <class T>
pybind11::array_t<T> hand_over(std::vector<T>&& values, std::vector<pybind11::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  pybind11::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return pybind11::array_t<T>(std::move(shape), owned->data(), owner);
}

}  // namespace sluice::python
