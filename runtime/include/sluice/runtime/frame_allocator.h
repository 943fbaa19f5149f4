// sluice/runtime/frame_allocator.h: where decoded frames live: the
// allocator a pipeline fills, the relay that sends frames kept encoded to
// device memory, and the block pool allocators keep their blocks in.
//
// The pipeline asks a FrameAllocator for the destination buffers of each
// frame before decoding it, and decode workers write straight into them: the
// renderer hands out persistently mapped staging memory, so a decoded chunk is
// written once, where the upload reads it. Buffers go back to the allocator
// when the pipeline no longer needs the frame (after the consumer released it
// and it has fallen out of the window).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sluice/io/format.h"

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
  // Where resident frames are filled from (frame_allocator.h); null when the
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
  std::unique_ptr<Pool> pool_;  // BlockPool (below)
};

// Relay: frames kept encoded, sent to device memory piece
// by piece as they are read.
//
// Without a relay, a frame kept encoded waits in host staging (the window)
// until the consumer commits it, and the GPU copies it from there: the
// staging has usually left the CPU's cache by then, and its bytes cross
// host memory three times. With one, a read thread copies a piece of
// the record out of the page cache into a small ring slot (plain stores),
// checks and plans its chunks while they are in the cache, and send()s it
// to the frame's place in device memory, where the window lives; the GPU
// reads the slot from the cache. docs/gpu_decode.md has the measurements.
//
// A FrameAllocator offers a relay (FrameAllocator::relay()) when it can
// hand out resident frames (FrameLayout::resident). The pipeline then uses
// it for frames kept encoded and checked as they are read.

// Threads: claim(), send() and give_back() are called from the pipeline's
// read threads, several at once. Every claimed piece is followed by
// exactly one send() or give_back() of it, on the thread that claimed it.
class PieceRelay {
 public:
  virtual ~PieceRelay() = default;
  // The most bytes one piece holds.
  virtual uint64_t piece_bytes() const = 0;
  // Host memory for a piece of `bytes` (<= piece_bytes()) to be written
  // with plain stores. Blocks while every ring slot is claimed or still
  // being copied. Throws a sluice::Error (the implementer's own) on a device error.
  virtual std::span<std::byte> claim(uint64_t bytes) = 0;
  // One range of a sent piece: `bytes` at `from` in the piece go to `to` in
  // the frame's staged area.
  struct Range {
    uint64_t from = 0, to = 0, bytes = 0;
  };
  // Submits the copy of `ranges` of `piece` into `frame`'s resident staged
  // area (buffers the same allocator handed out for a resident layout) and
  // returns at once; the slot goes back to the ring once the GPU has
  // copied it. A consumer of the frame waits for every copy sent into it
  // (the allocator's own bookkeeping). Throws a sluice::Error (the implementer's own) on a
  // device error (the piece is given back).
  virtual void send(std::span<std::byte> piece, const FrameBuffers& frame, std::span<const Range> ranges) = 0;
  // Gives a claimed piece back unsent (after an error).
  virtual void give_back(std::span<std::byte> piece) = 0;
};

// BlockPool: the block bookkeeping every FrameAllocator
// needs, whatever memory it hands out (host memory, Vulkan staging, ...).
//
// Released blocks are kept for reuse: a fresh allocation of a big frame costs
// a page fault per 4 KiB (a Vulkan allocation more). A request takes the
// smallest kept block that fits; when none fits, one kept block is freed
// first, so the number of blocks never exceeds the most that were in use at
// once and held_bytes() is what the window really costs. trim() gives kept
// blocks back when the window shrinks.
//
// Threads: acquire() and release() from one thread at a time (the
// FrameAllocator rule); the counters from any thread.

// `Memory` owns a block's bytes (freed when it is destroyed or replaced by a
// default-constructed one) and gives them out through data().
template <class Memory>
class BlockPool {
 public:
  struct Block {
    Memory memory;
    uint64_t capacity = 0;
    bool in_use = false;
  };

  // A block of at least `need` bytes, marked in use. `make(need)` returns new
  // Memory when no kept block fits; if it throws, the pool is unchanged but
  // for one empty kept block (reusable, holding nothing).
  template <class Make>
  Block& acquire(uint64_t need, Make&& make) {
    auto fits = kept_.end();
    for (auto it = kept_.begin(); it != kept_.end(); ++it) {
      if ((*it)->capacity >= need && (fits == kept_.end() || (*it)->capacity < (*fits)->capacity)) fits = it;
    }
    Block* block = nullptr;
    if (fits != kept_.end()) {
      block = *fits;
      kept_.erase(fits);
      kept_bytes_.fetch_sub(block->capacity, std::memory_order_relaxed);
    } else {
      if (!kept_.empty()) {  // give one kept block back first: the count does not grow
        block = kept_.back();
        kept_.pop_back();
        kept_bytes_.fetch_sub(block->capacity, std::memory_order_relaxed);
        account(-static_cast<int64_t>(block->capacity));
        block->memory = Memory{};
        block->capacity = 0;
      } else {
        blocks_.push_back(std::make_unique<Block>());
        block = blocks_.back().get();
        // Every block may be kept at once: release() then never allocates,
        // however the frames in flight come back.
        kept_.reserve(blocks_.size());
      }
      try {
        block->memory = make(need);
      } catch (...) {
        kept_.push_back(block);
        throw;
      }
      block->capacity = need;
      account(static_cast<int64_t>(need));
      allocations_.fetch_add(1, std::memory_order_relaxed);
    }
    block->in_use = true;
    in_use_.fetch_add(1, std::memory_order_relaxed);
    return *block;
  }

  // Back to the kept blocks (a block not in use is left alone).
  void release(Block& block) {
    if (!block.in_use) return;
    block.in_use = false;
    in_use_.fetch_sub(1, std::memory_order_relaxed);
    kept_.push_back(&block);
    kept_bytes_.fetch_add(block.capacity, std::memory_order_relaxed);
  }

  // Frees kept blocks, largest first, until at most `keep` bytes are kept;
  // blocks in use are never touched. Emptied blocks stay as reusable shells.
  void trim(uint64_t keep) {
    if (kept_bytes() <= keep) return;
    std::sort(kept_.begin(), kept_.end(), [](const Block* a, const Block* b) { return a->capacity > b->capacity; });
    for (Block* block : kept_) {
      if (kept_bytes() <= keep || block->capacity == 0) break;
      kept_bytes_.fetch_sub(block->capacity, std::memory_order_relaxed);
      account(-static_cast<int64_t>(block->capacity));
      block->memory = Memory{};
      block->capacity = 0;
    }
    // Shells last: acquire() takes the back one when no kept block fits.
    std::partition(kept_.begin(), kept_.end(), [](const Block* b) { return b->capacity > 0; });
  }

  // Bytes of the blocks, in use or kept, whose memory satisfies `pred` (for
  // an allocator with memory of several kinds). Same thread as acquire().
  template <class Pred>
  uint64_t held_where(Pred pred) const {
    uint64_t bytes = 0;
    for (const auto& block : blocks_) {
      if (block->capacity > 0 && pred(block->memory)) bytes += block->capacity;
    }
    return bytes;
  }

  uint64_t held_bytes() const { return held_.load(std::memory_order_relaxed); }        // in use + kept
  uint64_t kept_bytes() const { return kept_bytes_.load(std::memory_order_relaxed); }  // released, kept for reuse
  uint64_t peak_held_bytes() const { return peak_.load(std::memory_order_relaxed); }
  uint64_t in_use_blocks() const { return in_use_.load(std::memory_order_relaxed); }
  uint64_t allocations() const { return allocations_.load(std::memory_order_relaxed); }  // fresh, not reused

 private:
  void account(int64_t delta) {
    const uint64_t now =
        held_.fetch_add(static_cast<uint64_t>(delta), std::memory_order_relaxed) + static_cast<uint64_t>(delta);
    uint64_t peak = peak_.load(std::memory_order_relaxed);
    while (now > peak && !peak_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
    }
  }

  std::vector<std::unique_ptr<Block>> blocks_;  // every block (addresses stay put)
  std::vector<Block*> kept_;                    // released, ready for reuse
  std::atomic<uint64_t> held_{0}, peak_{0}, in_use_{0}, allocations_{0}, kept_bytes_{0};
};

// A frame's buffers in one block: the particles, then each attribute stream,
// every part starting on an `alignment` boundary.
struct BlockLayout {
  uint64_t attribute_offset = 0;  // of the first stream
  uint64_t attribute_stride = 0;  // between streams
  uint64_t bytes = 0;             // the whole block (at least `alignment`)
};
BlockLayout block_layout(const FrameLayout& layout, uint64_t alignment);
// The buffers of `layout` laid out from `base` as block_layout() says.
FrameBuffers lay_out_frame(std::byte* base, const FrameLayout& layout, const BlockLayout& at, uint64_t tag);

}  // namespace sluice::runtime
