// Internal: the memory of one frame block handed out by StagingAllocator,
// shared with upload.cpp, which copies from it.
#pragma once

#include <atomic>
#include <cstdlib>
#include <memory>

#include "relay_ring.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/runtime/frame_allocator.h"
#include "vk_common.h"

namespace sluice::render {

struct StagingAllocator::Memory {
  struct Free {
    void operator()(std::byte* p) const { std::free(p); }
  };
  Buffer staging;                          // host-visible, mapped; empty for a host fallback
  std::unique_ptr<std::byte, Free> host;   // the fallback's memory (aligned_alloc)
  uint64_t attribute_offset = 0;           // of the first attribute stream, in bytes (the frame in it now)
  uint64_t attribute_stride = 0;           // between streams
  std::unique_ptr<ResidentArea> area;      // a resident frame's (runtime::FrameLayout::resident)
  bool resident() const { return area != nullptr; }

  std::byte* data() const { return host ? host.get() : static_cast<std::byte*>(staging.mapped); }
};

class StagingAllocator::Pool : public runtime::BlockPool<Memory> {};

// The memory behind buffers a StagingAllocator handed out.
inline const StagingAllocator::Memory& staging_memory(const runtime::FrameBuffers& buffers) {
  return reinterpret_cast<const StagingAllocator::Pool::Block*>(static_cast<uintptr_t>(buffers.tag))->memory;
}
inline StagingAllocator::Memory& staging_memory_of(const runtime::FrameBuffers& buffers) {
  return reinterpret_cast<StagingAllocator::Pool::Block*>(static_cast<uintptr_t>(buffers.tag))->memory;
}

}  // namespace sluice::render
