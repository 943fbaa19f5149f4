// sluice/io/inline_vector.h: a vector of at most N elements held inline, for
// the per-chunk and per-frame lists whose size a format limit bounds
// (attributes: 32), so that filling them again never allocates.
#pragma once

#include <array>
#include <cstddef>

#include "sluice/io/error.h"

namespace sluice::io {

template <class T, size_t N>
class InlineVector {
 public:
  size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  static constexpr size_t capacity() { return N; }
  // Throws io::Error beyond N.
  void resize(size_t n, const T& value = T{}) {
    if (n > N) throw io::Error({}, "InlineVector: more than its capacity");
    for (size_t i = count_; i < n; ++i) items_[i] = value;
    count_ = n;
  }
  void assign(size_t n, const T& value) {
    count_ = 0;
    resize(n, value);
  }
  void clear() { count_ = 0; }
  template <class... Args>
  T& emplace_back(Args&&... args) {
    if (count_ == N) throw io::Error({}, "InlineVector: more than its capacity");
    items_[count_] = T(static_cast<Args&&>(args)...);
    return items_[count_++];
  }
  void push_back(const T& value) { emplace_back(value); }
  T& operator[](size_t i) { return items_[i]; }
  const T& operator[](size_t i) const { return items_[i]; }
  T* begin() { return items_.data(); }
  T* end() { return items_.data() + count_; }
  const T* begin() const { return items_.data(); }
  const T* end() const { return items_.data() + count_; }
  T* data() { return items_.data(); }
  const T* data() const { return items_.data(); }

 private:
  std::array<T, N> items_{};
  size_t count_ = 0;
};

}  // namespace sluice::io
