// Internal: one frame's memory handed out by StagingAllocator, shared with
// upload.cpp, which copies from it.
#pragma once

#include "sluice/render/staging_allocator.h"
#include "vk_common.h"

namespace sluice::render {

struct StagingAllocator::Block {
  Buffer staging;              // host-visible, mapped; empty for a host fallback
  std::byte* host = nullptr;   // the fallback's memory (aligned_alloc)
  uint64_t capacity = 0;
  uint64_t attribute_offset = 0;  // of the first attribute stream, in bytes
  uint64_t attribute_stride = 0;  // between streams
  bool in_use = false;

  std::byte* data() const { return host ? host : static_cast<std::byte*>(staging.mapped); }
  ~Block();
};

// The block behind buffers a StagingAllocator handed out.
inline const StagingAllocator::Block& staging_block(const runtime::FrameBuffers& buffers) {
  return *reinterpret_cast<const StagingAllocator::Block*>(static_cast<uintptr_t>(buffers.tag));
}

}  // namespace sluice::render
