// One frame's place in the pipeline, and the state machine it moves through.
//
//   Free -> Reading -> Decoding -> Ready -> Shown -> (returned) -> Cached -> Free
//                          |          \__________________________/   ^   |
//                          +-> Failed / Cancelled ---(returned)-> Free   +-> Ready (a cache hit)
//
// Empty frames and relayed ones (relay.h: checked and planned as read) go
// from Reading straight to Ready.
//
// Ownership follows the state, so each field has one writer at a time:
//  - the reader thread owns Free, Reading and Cached slots and fills them;
//  - decode workers own a Decoding slot's buffers; the worker that finishes
//    the last chunk moves it to Ready, Failed or Cancelled (release store);
//  - the consumer owns Ready and Shown slots it has taken, and gives every
//    slot back through the return ring, after which the reader owns it again.
// Slots are published by release stores of `state` or by the delivery ring,
// and read after the matching acquire.
#pragma once

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "read_runs.h"
#include "sluice/io/format.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/particles.h"
#include "sluice/runtime/demand.h"
#include "sluice/runtime/frame_allocator.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::runtime {

enum class SlotState : uint32_t {  // 32 bits: std::atomic::wait is a plain futex on it
  Free,
  Reading,
  Decoding,
  Ready,
  Failed,     // read, header or chunk error: `error` says which
  Cancelled,  // decode abandoned (stale generation, dropped, or shutting down)
  Shown,      // taken by the consumer
  Cached,     // decoded, returned, kept behind the playhead for reuse
};

inline constexpr uint32_t kNoRecord = ~0u;

struct Slot {
  std::atomic<SlotState> state{SlotState::Free};
  std::atomic<uint32_t> chunks_left{0};
  std::atomic<bool> abandoned{false};      // the consumer dropped it: skip chunks not started
  std::atomic<bool> skipped{false};        // some chunk was not decoded
  std::atomic<bool> error_claimed{false};  // a chunk has written `error`
  // A relayed read met a zstd plane: the frame is read again on the host
  // (written by read threads, read by the reader after the round's join).
  std::atomic<bool> relay_refused{false};

  // Written by the reader while it owns the slot.
  uint64_t frame = 0;
  uint64_t generation = 0;
  io::FrameHeader header;
  io::ErrorLocation where;                       // the file and this frame (no chunk): what decode errors name
  std::vector<uint64_t> chunk_first;             // first particle of each chunk
  FrameLayout layout;
  FrameBuffers buffers;
  bool has_buffers = false;
  std::vector<uint16_t*> attribute_targets;      // per header attribute; nullptr where not decoded
  io::ParticleSpans world;                       // DecodeMode::World: the arrays in `buffers.particles`
  // Set by the consumer while it holds the handle (FrameHandle::spoil),
  // read by the reader once the slot is back: its buffers were changed, so
  // the frame is never served again from them.
  bool spoiled = false;
  uint32_t record = kNoRecord;                   // record buffer in use while decoding
  std::span<const std::byte> record_bytes;       // the frame record inside it (or the prefix the wanted layers need)
  bool table_parsed = false;                     // the table was read first and parsed (`header`) before the payloads
  bool checked_on_read = false;                  // the wanted chunks were checked as they were read (checksums)
  bool relayed = false;  // ... and sent to a resident area through the relay (frame_allocator.h)
  std::vector<io::RecordPart> parts;             // checked reads and reads by demand: the records' parts to read (io::record_parts)
  std::vector<uint32_t> piece_cuts;              // checked reads: piece p reads parts [cuts[p], cuts[p + 1])
  std::vector<detail::ByteRun> runs;             // reads by demand: the pieces of the runs (read_runs.h)
  uint32_t run_count = 0;                        // ... and how many runs they are
  io::GpuDecodePlan plan;                        // DecodeMode::KeepEncoded: what the workers stage
  std::vector<CellRead> cells;                   // every cell of the frame and the tiers read of it (demand.h)
  bool demand_applied = false;                   // `header` holds the demanded tiers only, `cells` is filled
  bool by_demand = false;                        // read in runs of the wanted records, for a demand that leaves tiers out

  // Written by the reader (read errors) or the chunk that won error_claimed.
  FrameError error;
};

// What the reader hands the consumer, in schedule order.
struct Entry {
  uint32_t slot = 0;
  uint64_t generation = 0;
  uint64_t sequence = 0;
  uint64_t frame = 0;
};

// Claims the frame's error (the first one wins, from any thread) and
// records what `describe()` returns; never throws: without memory to
// describe it the message stays empty and the consumer says so.
template <class Describe>
void claim_error(Slot& slot, Describe describe) noexcept {
  if (slot.error_claimed.exchange(true, std::memory_order_acq_rel)) return;
  try {
    slot.error = describe();
  } catch (...) {
    // No memory to say why: name the frame (no allocation) and leave the
    // message empty.
    slot.error.where.frame = slot.frame;
    slot.error.where.chunk.reset();
    slot.error.message.clear();
  }
}

}  // namespace sluice::runtime
