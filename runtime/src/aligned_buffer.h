// A heap buffer with a chosen alignment (O_DIRECT wants 4096), grown by
// replacement: contents are not kept.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <span>

namespace sluice::runtime {

class AlignedBuffer {
 public:
  static constexpr size_t kAlignment = 4096;

  AlignedBuffer() = default;
  ~AlignedBuffer() { std::free(data_); }
  AlignedBuffer(const AlignedBuffer&) = delete;
  AlignedBuffer& operator=(const AlignedBuffer&) = delete;

  // Makes room for `bytes`; throws std::bad_alloc.
  void reserve(size_t bytes) {
    if (bytes <= capacity_) return;
    const size_t rounded = (bytes + kAlignment - 1) / kAlignment * kAlignment;
    void* fresh = std::aligned_alloc(kAlignment, rounded);
    if (!fresh) throw std::bad_alloc();
    std::free(data_);
    data_ = static_cast<std::byte*>(fresh);
    capacity_ = rounded;
  }
  void release() {
    std::free(data_);
    data_ = nullptr;
    capacity_ = 0;
  }
  std::span<std::byte> span() { return {data_, capacity_}; }
  size_t capacity() const { return capacity_; }

 private:
  std::byte* data_ = nullptr;
  size_t capacity_ = 0;
};

}  // namespace sluice::runtime
