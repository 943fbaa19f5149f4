#include <algorithm>
#include <cstdlib>
#include <new>

#include "sluice/runtime/frame_allocator.h"

namespace sluice::runtime {
namespace {

constexpr size_t kAlignment = 64;  // a cache line: streams never share one

uint64_t align_up(uint64_t n, uint64_t alignment) { return (n + alignment - 1) / alignment * alignment; }

}  // namespace

BlockLayout block_layout(const FrameLayout& layout, uint64_t alignment) {
  BlockLayout b;
  b.attribute_offset = align_up(layout.particle_bytes(), alignment);
  b.attribute_stride = align_up(layout.attribute_bytes(), alignment);
  b.bytes = std::max<uint64_t>(alignment, b.attribute_offset + layout.attribute_streams * b.attribute_stride);
  return b;
}

FrameBuffers lay_out_frame(std::byte* base, const FrameLayout& layout, const BlockLayout& at, uint64_t tag) {
  FrameBuffers out;
  out.tag = tag;
  out.particles = {base, layout.particle_bytes()};
  for (uint32_t s = 0; s < layout.attribute_streams; ++s) {
    out.attributes.emplace_back(reinterpret_cast<uint16_t*>(base + at.attribute_offset + s * at.attribute_stride), layout.particles);
  }
  return out;
}

struct HostFrameAllocator::Memory {
  struct Free {
    void operator()(std::byte* p) const { std::free(p); }
  };
  std::unique_ptr<std::byte, Free> bytes;
};

HostFrameAllocator::HostFrameAllocator() : pool_(std::make_unique<Pool>()) {}
HostFrameAllocator::~HostFrameAllocator() = default;

uint64_t HostFrameAllocator::bytes_for(const FrameLayout& layout) const { return block_layout(layout, kAlignment).bytes; }

FrameBuffers HostFrameAllocator::allocate(const FrameLayout& layout) {
  const BlockLayout at = block_layout(layout, kAlignment);
  Pool::Block& block = pool_->acquire(at.bytes, [](uint64_t need) {
    Memory m;
    m.bytes.reset(static_cast<std::byte*>(std::aligned_alloc(kAlignment, need)));
    if (!m.bytes) throw std::bad_alloc();
    return m;
  });
  return lay_out_frame(block.memory.bytes.get(), layout, at, reinterpret_cast<uintptr_t>(&block));
}

void HostFrameAllocator::release(FrameBuffers& buffers) {
  if (!buffers.tag) return;
  pool_->release(*reinterpret_cast<Pool::Block*>(static_cast<uintptr_t>(buffers.tag)));
  buffers = {};
}

uint64_t HostFrameAllocator::kept_bytes() const { return pool_->kept_bytes(); }
void HostFrameAllocator::trim(uint64_t keep) { pool_->trim(keep); }
uint64_t HostFrameAllocator::held_bytes() const { return pool_->held_bytes(); }
uint64_t HostFrameAllocator::peak_held_bytes() const { return pool_->peak_held_bytes(); }
uint64_t HostFrameAllocator::in_use_buffers() const { return pool_->in_use_blocks(); }
uint64_t HostFrameAllocator::allocations() const { return pool_->allocations(); }

}  // namespace sluice::runtime
