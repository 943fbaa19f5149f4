// Internal: the memory of one frame block handed out by StagingAllocator
// (staging_allocator.cpp), and how to find it from the buffers handed out.
#pragma once

#include <atomic>
#include <cstdlib>
#include <memory>

#include "relay_ring.h"
#include "sluice/runtime/frame_allocator.h"
#include "vk_common.h"

namespace sluice::render {

struct StagingBlock {
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

class StagingPool : public runtime::BlockPool<StagingBlock> {};

// The memory behind buffers a StagingAllocator handed out.
inline const StagingBlock& staging_memory(const runtime::FrameBuffers& buffers) {
  return reinterpret_cast<const StagingPool::Block*>(static_cast<uintptr_t>(buffers.tag))->memory;
}
inline StagingBlock& staging_memory_of(const runtime::FrameBuffers& buffers) {
  return reinterpret_cast<StagingPool::Block*>(static_cast<uintptr_t>(buffers.tag))->memory;
}

}  // namespace sluice::render
