// sluice/runtime/block_pool.h: the block bookkeeping every FrameAllocator
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
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "sluice/runtime/frame_allocator.h"

namespace sluice::runtime {

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

  uint64_t held_bytes() const { return held_.load(std::memory_order_relaxed); }  // in use + kept
  uint64_t kept_bytes() const { return kept_bytes_.load(std::memory_order_relaxed); }  // released, kept for reuse
  uint64_t peak_held_bytes() const { return peak_.load(std::memory_order_relaxed); }
  uint64_t in_use_blocks() const { return in_use_.load(std::memory_order_relaxed); }
  uint64_t allocations() const { return allocations_.load(std::memory_order_relaxed); }  // fresh, not reused

 private:
  void account(int64_t delta) {
    const uint64_t now = held_.fetch_add(static_cast<uint64_t>(delta), std::memory_order_relaxed) + static_cast<uint64_t>(delta);
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
