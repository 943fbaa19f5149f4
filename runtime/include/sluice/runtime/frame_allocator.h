// sluice/runtime/frame_allocator.h: where decoded frames live.
//
// The pipeline asks a FrameAllocator for the destination buffers of each
// frame before decoding it, and decode workers write straight into them: the
// renderer hands out persistently mapped staging memory, so a decoded chunk is
// written once, where the upload reads it. Buffers go back to the allocator
// when the pipeline no longer needs the frame (after the consumer released it
// and it has fallen out of the window).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sluice/io/inline_vector.h"

namespace sluice::runtime {

template <class Memory>
class BlockPool;
class PieceRelay;

// What one frame needs. Sizes come from the frame index.
struct FrameLayout {
  uint64_t frame = 0;              // frame number in the file (for the allocator's logs)
  uint64_t particles = 0;
  uint32_t particle_stride = 8;    // decoded bytes per particle (io::decoded_particle_bytes)
  uint32_t attribute_streams = 0;  // uint16 streams of `particles` values each
  // > 0: the frame stays encoded for a GPU decoder (DecodeMode::
  // KeepEncoded): FrameBuffers::particles then holds these bytes, the
  // staged area of io/gpu_decode_plan.h (payloads, inflated planes, chunk
  // plans, tile table; staged_bytes() of them, the rest unused), and there
  // are no attribute streams.
  uint64_t encoded_bytes = 0;
  // With encoded_bytes: the staged area lives in device memory, filled
  // through the allocator's relay() as it is read; FrameBuffers::particles
  // is then empty (the plan's tables travel with the plan). Only for an
  // allocator that offers a relay.
  bool resident = false;

  uint64_t particle_bytes() const {
    if (resident) return 0;
    return encoded_bytes > 0 ? encoded_bytes : particles * particle_stride;
  }
  uint64_t attribute_bytes() const { return particles * 2; }  // per stream
  uint64_t total_bytes() const { return particle_bytes() + attribute_streams * attribute_bytes(); }
};

// The bytes to ask for an encoded frame of `staged` bytes: rounded up to a
// step of at most 1/16 of it, so frames of slightly different sizes share a
// kept block instead of each replacing it (the allocator keeps its rule of
// never holding more than the blocks asked for).
inline uint64_t encoded_block_bytes(uint64_t staged) {
  uint64_t step = 4096;
  while (step * 16 <= staged) step *= 2;
  return (staged + step - 1) / step * step;
}

// The buffers of one frame. Memory is owned by the allocator.
struct FrameBuffers {
  std::span<std::byte> particles;               // >= layout.particle_bytes(), 16-byte aligned
  // layout.attribute_streams spans of >= particles values (held inline:
  // handing out buffers allocates nothing).
  io::InlineVector<std::span<uint16_t>, 32> attributes;
  uint64_t tag = 0;                             // the allocator's own (a staging offset, an index, ...)
};

// Threads: the pipeline calls allocate() and release() from one thread at a
// time (its reader thread, and the thread destroying it once the reader has
// stopped), so an implementation needs no lock of its own. Decode workers
// write into the buffers between the two calls; nothing else touches them.
class FrameAllocator {
 public:
  virtual ~FrameAllocator() = default;
  // Returns buffers of at least the layout's sizes. May throw (std::bad_alloc
  // or io::Error): the pipeline reports it as an error of that frame.
  virtual FrameBuffers allocate(const FrameLayout& layout) = 0;
  // Takes back buffers allocate() returned.
  virtual void release(FrameBuffers& buffers) = 0;
  // Bytes an allocation of `layout` really takes (alignment, padding): the
  // window is sized with it. Any thread.
  virtual uint64_t bytes_for(const FrameLayout& layout) const { return layout.total_bytes(); }
  // Bytes of released buffers kept for reuse (not in use): the pipeline
  // counts them as its own when it plans the window. Any thread.
  virtual uint64_t kept_bytes() const { return 0; }
  // Frees kept buffers until at most `keep` bytes are kept: the pipeline
  // calls it when the window shrinks, so memory held follows the window.
  // Same thread rule as allocate() and release().
  virtual void trim(uint64_t keep) { (void)keep; }
  // Where resident frames are filled from (relay.h); null when the
  // allocator hands out host memory only. Borrowed: lives as long as the
  // allocator.
  virtual PieceRelay* relay() { return nullptr; }
};

// Host memory with byte accounting, for headless playback, benchmarks and
// the memory tests. Released buffers are kept for reuse (a fresh allocation
// of a big frame costs a page fault per 4 KiB); the number of buffers alive,
// in use or kept, never exceeds the most that were in use at once, so
// held_bytes() is what the window really costs.
class HostFrameAllocator final : public FrameAllocator {
 public:
  HostFrameAllocator();
  ~HostFrameAllocator() override;
  HostFrameAllocator(const HostFrameAllocator&) = delete;
  HostFrameAllocator& operator=(const HostFrameAllocator&) = delete;

  FrameBuffers allocate(const FrameLayout& layout) override;
  void release(FrameBuffers& buffers) override;
  uint64_t bytes_for(const FrameLayout& layout) const override;
  uint64_t kept_bytes() const override;
  void trim(uint64_t keep) override;

  // Readable from any thread.
  uint64_t held_bytes() const;       // in use + kept
  uint64_t peak_held_bytes() const;
  uint64_t in_use_buffers() const;
  uint64_t allocations() const;      // fresh, not reused

 private:
  struct Memory;
  using Pool = BlockPool<Memory>;
  std::unique_ptr<Pool> pool_;  // block_pool.h
};

}  // namespace sluice::runtime
