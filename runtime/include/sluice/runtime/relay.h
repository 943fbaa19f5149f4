// sluice/runtime/relay.h: frames kept encoded, sent to device memory piece
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
#pragma once

#include <cstdint>
#include <span>

#include "sluice/runtime/frame_allocator.h"

namespace sluice::runtime {

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

}  // namespace sluice::runtime
