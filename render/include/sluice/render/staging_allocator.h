// sluice/render/staging_allocator.h: the runtime's frame buffers in Vulkan
// staging memory.
//
// A runtime::FrameAllocator whose buffers are persistently mapped,
// host-visible Vulkan buffers: the pipeline's decode workers write a frame
// straight into memory the GPU copies from (Renderer::commit_decoded), so a
// decoded particle is written once and never copied on the CPU. Where the
// driver refuses more host-visible memory, a frame falls back to ordinary
// host memory and the renderer copies it through its own staging (counted in
// fallback_allocations()).
//
// Ownership: borrows the Context, which must outlive it (and every frame it
// handed out). Threads: allocate()/release() as runtime::FrameAllocator says
// (one thread at a time); the counters and device_budget() from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "sluice/render/context.h"
#include "sluice/runtime/block_pool.h"
#include "sluice/runtime/budget.h"
#include "sluice/runtime/frame_allocator.h"

namespace sluice::render {

class StagingAllocator final : public runtime::FrameAllocator {
 public:
  explicit StagingAllocator(Context& context);
  ~StagingAllocator() override;
  StagingAllocator(const StagingAllocator&) = delete;
  StagingAllocator& operator=(const StagingAllocator&) = delete;

  runtime::FrameBuffers allocate(const runtime::FrameLayout& layout) override;
  void release(runtime::FrameBuffers& buffers) override;
  uint64_t bytes_for(const runtime::FrameLayout& layout) const override;
  uint64_t kept_bytes() const override;
  void trim(uint64_t keep) override;

  // The budget to give the pipeline for device memory: the free part of the
  // heap staging memory comes from (VK_EXT_memory_budget), plus what this
  // allocator already holds there, when that heap is device-local (integrated
  // GPUs, lavapipe, resizable BAR); nullptr when staging lives in system
  // memory, where the host budget already covers it.
  const runtime::DeviceMemoryBudget* device_budget() const;
  bool staging_in_device_heap() const { return device_heap_; }

  uint64_t held_bytes() const;
  uint64_t peak_held_bytes() const;
  uint64_t fallback_allocations() const { return fallbacks_.load(std::memory_order_relaxed); }
  uint64_t fresh_allocations() const;  // blocks made anew (not reused): each a Vulkan allocation

  struct Memory;  // render/src/staging_block.h: a block's staging buffer (or host fallback)
  using Pool = runtime::BlockPool<Memory>;  // FrameBuffers::tag points at one of its blocks

 private:
  class HeapBudget;

  Context& context_;
  std::unique_ptr<Pool> pool_;
  bool device_heap_ = false;
  uint32_t heap_ = 0;
  std::unique_ptr<HeapBudget> budget_;
  std::atomic<uint64_t> fallbacks_{0};
};

}  // namespace sluice::render
