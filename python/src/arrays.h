// Hands C++ vectors to numpy without copying: the array's base is a
// capsule owning the vector, so the array keeps its memory alive after the
// sequence or frame it came from is gone. Vectors handed over through an
// ArrayPool go back to it when their array dies, and the next frame of a
// stream takes their memory over (no page faulted in or cleared again).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <vector>

namespace sluice::python {

template <class T>
pybind11::array_t<T> hand_over(std::vector<T>&& values, std::vector<pybind11::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  pybind11::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return pybind11::array_t<T>(std::move(shape), owned->data(), owner);
}

// Spare vectors of the element types frames hold. Threads: any (a mutex);
// arrays die on the Python thread, streams take on their own.
class ArrayPool : public std::enable_shared_from_this<ArrayPool> {
 public:
  // A spare vector (empty when there is none), the largest first.
  template <class T>
  std::vector<T> take() {
    std::lock_guard lock(mutex_);
    auto& spares = list<T>();
    if (spares.empty()) return {};
    std::vector<T> v = std::move(spares.back());
    spares.pop_back();
    return v;
  }

  // As hand_over(), the vector returning here when the array dies.
  template <class T>
  pybind11::array_t<T> hand_over(std::vector<T>&& values, std::vector<pybind11::ssize_t> shape) {
    struct Owned {
      std::vector<T> values;
      std::shared_ptr<ArrayPool> pool;
    };
    auto* owned = new Owned{std::move(values), shared_from_this()};
    pybind11::capsule owner(owned, [](void* p) {
      auto* o = static_cast<Owned*>(p);
      o->pool->give_back(std::move(o->values));
      delete o;
    });
    return pybind11::array_t<T>(std::move(shape), owned->values.data(), owner);
  }

 private:
  static constexpr size_t kMostSpares = 8;  // per type: a few frames' arrays

  template <class T>
  void give_back(std::vector<T>&& v) {
    std::lock_guard lock(mutex_);
    auto& spares = list<T>();
    if (spares.size() < kMostSpares) spares.push_back(std::move(v));
  }
  template <class T>
  std::vector<std::vector<T>>& list() {
    if constexpr (std::is_same_v<T, float>) return floats_;
    else if constexpr (std::is_same_v<T, uint16_t>) return u16_;
    else return u8_;
  }

  std::mutex mutex_;
  std::vector<std::vector<float>> floats_;
  std::vector<std::vector<uint16_t>> u16_;
  std::vector<std::vector<uint8_t>> u8_;
};

}  // namespace sluice::python
