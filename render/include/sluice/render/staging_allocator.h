// sluice/render/staging_allocator.h: the runtime's frame buffers in Vulkan
// staging memory.
//
// A runtime::FrameAllocator whose buffers are persistently mapped,
// host-visible Vulkan buffers: the pipeline's decode workers write a frame
// straight into memory the GPU copies from (Renderer::commit), so a
// decoded particle is written once and never copied on the CPU. Where the
// driver refuses more host-visible memory, a frame falls back to ordinary
// host memory and the renderer copies it through its own staging (counted in
// fallback_allocations()).
//
// With a resident window (StagingOptions::resident), frames kept encoded
// live in device memory instead, filled through a small ring of staging
// slots as they are read (runtime/frame_allocator.h): relay() offers the ring, and a
// pipeline kept encoded uses it for every frame it reads in place. The
// window then costs device memory (device_budget() plans it), and the host
// holds the ring only.
//
// Ownership: borrows the Context, which must outlive it (and every frame it
// handed out). Threads: allocate()/release() as runtime::FrameAllocator says
// (one thread at a time); the counters and device_budget() from any thread;
// the relay as frame_allocator.h says (it submits on the context's relay queue: see
// context.h, "Queues").
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "sluice/render/context.h"
#include "sluice/render/frame.h"
#include "sluice/runtime/budget.h"
#include "sluice/runtime/frame_allocator.h"

namespace sluice::runtime {
class FrameHandle;
}  // namespace sluice::runtime

namespace sluice::render {

class RelayRing;
struct StagingBlock;  // render/src/staging_block.h: a block's staging buffer (or host fallback)
class StagingPool;    // render/src/staging_block.h: FrameBuffers::tag points at one of its blocks

// Where the relay's ring lives in host memory.
enum class RingMemory : uint8_t {
  // Host-visible, cached memory the driver allocates.
  Driver,
  // Anonymous memory sluice maps and the device imports
  // (VK_EXT_external_memory_host); the driver's memory where the device
  // cannot import it (StagingAllocator::ring_imported() says which).
  Imported,
};

struct StagingOptions {
  // Frames kept encoded live in device memory, relayed through a ring.
  bool resident = false;
  // The ring: `ring_slots` slots of `ring_piece_bytes` (0: the read threads
  // a pipeline has by default on the machine it runs on, plus 4;
  // docs/gpu_decode.md measures slot counts and sizes).
  uint32_t ring_slots = 0;
  uint64_t ring_piece_bytes = 8 << 20;
  RingMemory ring_memory = RingMemory::Driver;  // docs/measurements.md, "The relay's sends"
};

class StagingAllocator final : public runtime::FrameAllocator {
 public:
  explicit StagingAllocator(Context& context, const StagingOptions& options = {});
  ~StagingAllocator() override;
  StagingAllocator(const StagingAllocator&) = delete;
  StagingAllocator& operator=(const StagingAllocator&) = delete;

  runtime::FrameBuffers allocate(const runtime::FrameLayout& layout) override;
  void release(runtime::FrameBuffers& buffers) override;
  uint64_t bytes_for(const runtime::FrameLayout& layout) const override;
  uint64_t kept_bytes() const override;
  void trim(uint64_t keep) override;
  runtime::PieceRelay* relay() override;  // null without a resident window
  bool resident() const { return options_.resident; }
  // The ring's shape (0 slots without a resident window).
  uint32_t ring_slots() const;
  uint64_t ring_piece_bytes() const;
  bool ring_imported() const;  // the ring is imported host memory (RingMemory::Imported, and the device took it)
  // The ring's timeline semaphore, which a resident frame's decode waits on
  // (null without a resident window).
  VkSemaphore relay_semaphore() const;

  // The budget to give the pipeline for device memory: the free part of the
  // heap staging memory comes from (VK_EXT_memory_budget), plus what this
  // allocator already holds there, when that heap is device-local (integrated
  // GPUs, lavapipe, resizable BAR); nullptr when staging lives in system
  // memory, where the host budget already covers it. With a resident
  // window: the device-local heap's free part plus the areas held.
  const runtime::DeviceMemoryBudget* device_budget() const;

  uint64_t held_bytes() const;
  uint64_t peak_held_bytes() const;
  uint64_t fallback_allocations() const { return fallbacks_.load(std::memory_order_relaxed); }
  uint64_t fresh_allocations() const;  // blocks made anew (not reused): each a Vulkan allocation

 private:
  class HeapBudget;

  Context& context_;
  StagingOptions options_;
  std::unique_ptr<RelayRing> ring_;      // before the pools: their resident areas wait on it when destroyed
  std::unique_ptr<StagingPool> pool_;
  std::unique_ptr<StagingPool> resident_pool_;  // device areas
  uint32_t device_local_heap_ = 0;
  bool device_heap_ = false;
  uint32_t heap_ = 0;
  std::unique_ptr<HeapBudget> budget_;
  std::atomic<uint64_t> fallbacks_{0};
};

// A frame the streaming runtime delivered, as Renderer::commit() takes it:
// its header, chunk starts and bytes (decoded, or kept encoded with its GPU
// plan), with the Vulkan buffers they lie in when `from` (this allocator, of
// the renderer's Context) handed out the frame's buffers; null: the frame's
// buffers are in host memory. The colour is the frame's attribute
// `color_attribute` (file header index; -1: none), from attribute streams
// that hold every attribute or only that one (PipelineOptions::decode).
// The handle must outlive the upload (Renderer::upload_complete()). Throws
// render::Error for an empty or failed handle, a frame in world units
// (DecodeMode::World: for array consumers) or a colour it does not hold.
FrameUpload frame_upload(const runtime::FrameHandle& frame, int color_attribute, const StagingAllocator* from);

}  // namespace sluice::render
