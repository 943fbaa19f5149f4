// The reader thread's window: which slots are free, kept behind the
// playhead (cached) or still decoding after their return (draining); how
// many may be in use (the memory plan, grown by slow start); the record
// buffers; and the bytes the pipeline holds.
//
// Threads: the reader thread alone calls every member, so nothing here is
// synchronised. What other threads tell it arrives through the slots'
// states (read with acquire: the workers' and the consumer's release
// stores) and the record return ring (an MPSC ring, popped here only).
// It writes the pipeline's window and memory counters (relaxed stores, read
// by stats()).
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <vector>

#include "aligned_buffer.h"
#include "counters.h"
#include "mpsc_ring.h"
#include "slot.h"
#include "sluice/runtime/frame_allocator.h"
#include "sluice/runtime/pipeline.h"
#include "sluice/runtime/budget.h"

namespace sluice::runtime::detail {

// Frames the reader keeps ahead of the playhead (delivered and not yet
// released ones count) in a window of `frames`: the rest is kept for frames
// behind it.
inline uint32_t ahead_most(uint32_t frames) { return frames - frames / 4; }

class SlotWindow {
 public:
  // What the window works on, owned by the pipeline and outliving it.
  struct Parts {
    Slot* slots = nullptr;
    uint32_t slot_count = 0;
    std::vector<AlignedBuffer>* records = nullptr;
    FrameAllocator* allocator = nullptr;
    Counters* counters = nullptr;
    const WindowSettings* options = nullptr;
    FrameFootprint footprint;
    uint64_t file_frames = 0;  // frames in the file: no more slots than that are planned
    int decode_threads = 1;
    const std::atomic<uint32_t>* frames_decoding = nullptr;  // frames with the workers (grow() waits for none)
  };

  // Plans the window from what memory allows now, `held` bytes counted as
  // the pipeline's (made on the constructing thread, before the reader's).
  static WindowPlan plan(const Parts& parts, uint64_t held);
  // The slots in use at first: the whole plan, or a few with slow start.
  static uint32_t initial_active(const Parts& parts, const WindowPlan& plan);

  SlotWindow(const Parts& parts, const WindowPlan& initial);

  // --- the window's size ---
  uint32_t ahead_limit() const { return ahead_most(active_); }
  // Slot count in use: `in_flight` (published and not returned, or read in
  // the background) plus the cached and draining ones.
  uint32_t occupied(uint32_t in_flight) const;
  // Slow start: one slot more while the reader is ahead and decoding idle;
  // false when the plan is reached or the workers are busy.
  bool grow();
  // Every few frames started: plans again from memory and follows a change
  // worth an eighth of the window (on_change is told).
  void reevaluate_if_due();
  // Evicts cached frames beyond the active count and trims the allocator's
  // kept buffers to the free slots' worth (`unbuffered`: background reads
  // that will still take buffers).
  void shrink(uint32_t in_flight, uint32_t unbuffered);

  // --- slots ---
  // A slot back from the consumer: kept (cached) if it holds a good frame,
  // waiting if still decoding, else freed.
  void returned(uint32_t s);
  // Draining slots whose decode has ended are settled.
  void settle_drained();
  // The newest cached copy of `frame`, taken off the cached list.
  std::optional<uint32_t> take_cached(uint64_t frame);
  // A free slot and record buffer for a new read, evicting cached frames for
  // room; nullopt while the window or the record buffers are full.
  struct Claim {
    uint32_t slot, record;
  };
  std::optional<Claim> claim(uint32_t in_flight);
  void free_slot(uint32_t s);
  void count_started() { ++frames_started_; }

  // --- buffers ---
  void allocate_buffers(Slot& slot);
  void release_buffers(Slot& slot);
  // `slot` takes `buffers` (laid out as `layout`) in place of its own.
  void replace_buffers(Slot& slot, const FrameLayout& layout, const FrameBuffers& buffers);
  // Record buffer `record`, grown to at least `bytes` (counted as held).
  AlignedBuffer& record_buffer(uint32_t record, uint64_t bytes);
  void return_record(uint32_t record) { free_records_.push_back(record); }
  // Record buffers the workers gave back; memory beyond the plan's count
  // of buffers is released.
  void take_record_returns(MpscRing<uint32_t>& returns);

  uint64_t held() const;  // decoded buffers in use and kept, record buffers

 private:
  void settle(uint32_t s, SlotState state);
  bool evict_oldest();
  void publish_held() const;

  Parts parts_;
  WindowPlan plan_;
  uint32_t active_ = 2;                // slots in use at most: grows to plan_.frames (slow start)
  uint64_t frames_started_ = 0;
  uint64_t next_evaluation_ = 0;
  uint64_t decoded_held_ = 0;          // bytes of allocator buffers held
  uint64_t record_held_ = 0;           // bytes of record buffers held
  std::vector<uint32_t> free_slots_;
  std::vector<uint32_t> cached_;       // decoded frames behind the playhead, oldest first (a slot count at most)
  std::vector<uint32_t> draining_;     // returned while still decoding
  std::vector<uint32_t> free_records_; // record buffers not in use
};

}  // namespace sluice::runtime::detail
