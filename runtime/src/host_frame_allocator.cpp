#include "sluice/runtime/frame_allocator.h"

#include <algorithm>
#include <cstdlib>
#include <new>

namespace sluice::runtime {
namespace {

constexpr size_t kAlignment = 64;  // a cache line: streams never share one

uint64_t align_up(uint64_t n) { return (n + kAlignment - 1) / kAlignment * kAlignment; }

}  // namespace

struct HostFrameAllocator::Block {
  std::byte* memory = nullptr;
  uint64_t capacity = 0;
  bool in_use = false;
  ~Block() { std::free(memory); }
};

HostFrameAllocator::HostFrameAllocator() = default;
HostFrameAllocator::~HostFrameAllocator() = default;

void HostFrameAllocator::account(int64_t delta) {
  const uint64_t now = held_.fetch_add(static_cast<uint64_t>(delta), std::memory_order_relaxed) + static_cast<uint64_t>(delta);
  uint64_t peak = peak_.load(std::memory_order_relaxed);
  while (now > peak && !peak_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
  }
}

uint64_t HostFrameAllocator::bytes_for(const FrameLayout& layout) const {
  return std::max<uint64_t>(kAlignment,
                            align_up(layout.particle_bytes()) + layout.attribute_streams * align_up(layout.attribute_bytes()));
}

FrameBuffers HostFrameAllocator::allocate(const FrameLayout& layout) {
  const uint64_t stream = align_up(layout.attribute_bytes());
  const uint64_t need = bytes_for(layout);

  // Reuse the smallest kept block that fits; if none fits, give one kept
  // block back first so the count of blocks does not grow.
  auto fits = kept_.end();
  for (auto it = kept_.begin(); it != kept_.end(); ++it) {
    const uint64_t capacity = blocks_[*it]->capacity;
    if (capacity >= need && (fits == kept_.end() || capacity < blocks_[*fits]->capacity)) fits = it;
  }
  uint64_t tag;
  if (fits != kept_.end()) {
    tag = *fits;
    kept_.erase(fits);
  } else {
    if (!kept_.empty()) {
      Block& old = *blocks_[kept_.back()];
      account(-static_cast<int64_t>(old.capacity));
      std::free(old.memory);
      old.memory = nullptr;
      old.capacity = 0;
      tag = kept_.back();
      kept_.pop_back();
    } else {
      tag = blocks_.size();
      blocks_.push_back(std::make_unique<Block>());
    }
    Block& b = *blocks_[tag];
    b.memory = static_cast<std::byte*>(std::aligned_alloc(kAlignment, need));
    if (!b.memory) {
      kept_.push_back(tag);  // an empty block: reusable, costs nothing
      throw std::bad_alloc();
    }
    b.capacity = need;
    account(static_cast<int64_t>(need));
    allocations_.fetch_add(1, std::memory_order_relaxed);
  }
  Block& b = *blocks_[tag];
  b.in_use = true;
  in_use_.fetch_add(1, std::memory_order_relaxed);

  FrameBuffers out;
  out.tag = tag;
  out.particles = {b.memory, layout.particle_bytes()};
  std::byte* at = b.memory + align_up(layout.particle_bytes());
  for (uint32_t s = 0; s < layout.attribute_streams; ++s, at += stream) {
    out.attributes.emplace_back(reinterpret_cast<uint16_t*>(at), layout.particles);
  }
  return out;
}

void HostFrameAllocator::release(FrameBuffers& buffers) {
  Block& b = *blocks_.at(buffers.tag);
  if (!b.in_use) return;
  b.in_use = false;
  in_use_.fetch_sub(1, std::memory_order_relaxed);
  kept_.push_back(buffers.tag);
  buffers = {};
}

}  // namespace sluice::runtime
