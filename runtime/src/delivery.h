// Frames handed from the reader thread to the consumer in schedule order,
// and slots handed back.
//
// Threads: the reader thread calls publish() and take_return(); the one
// consumer thread (Pipeline's contract) calls everything else. Entries go
// through a single-producer single-consumer ring (reader -> consumer) and
// slots come back through another (consumer -> reader); neither push can
// fail, since each ring holds every slot at once. What a slot holds is
// published by its state's release store (slot.h), read here after an
// acquire load. Each side is woken through a counter it waits on
// (std::atomic::wait): the consumer's here, the reader's given in Parts.
#pragma once

#include <atomic>
#include <cstdint>

#include "counters.h"
#include "slot.h"
#include "spsc_ring.h"
#include "wake.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::runtime::detail {

class Delivery {
 public:
  // What delivery works on, owned by the pipeline and outliving it.
  struct Parts {
    Slot* slots = nullptr;
    uint32_t slot_count = 0;
    Counters* counters = nullptr;
    std::atomic<uint32_t>* reader_wake = nullptr;     // bumped when a slot comes back
    const std::atomic<bool>* reader_failed = nullptr;  // no more entries will come
  };
  explicit Delivery(const Parts& parts);

  // --- the reader thread ---
  void publish(const Entry& entry);
  bool take_return(uint32_t& slot) { return returns_.try_pop(slot); }
  // Wakes a consumer waiting in wait_next() (an entry, or the reader's end).
  void wake_consumer() { wake(consumer_wake_); }

  // --- the consumer thread ---
  // A new schedule, already handed to the reader as `generation`: entries of
  // older generations are given back as they are met.
  void begin(const PlaybackSchedule& schedule, uint64_t generation);
  const PlaybackSchedule& schedule() const { return schedule_; }
  uint64_t generation() const { return generation_; }
  NextEntry peek(size_t i);
  // Blocks until the next entry is ready or failed, or the schedule ends.
  // Throws Error when the consumer holds all the reader may keep ahead in
  // a window of `window_frames`.
  NextEntry wait_next();
  // The next entry, taken off the ring (Pipeline::take's checks first);
  // `state` is its slot's state as taken: Ready or Failed.
  struct Taken {
    Entry entry;
    SlotState state = SlotState::Free;
  };
  Taken take();
  void drop();
  uint32_t ready_count();
  // A slot back to the reader (a dropped entry, a failed handle).
  void give_back(uint32_t slot);
  // A handle taken: counted until its release() (which gives its slot back).
  void hold() { ++handles_held_; }
  void release(uint32_t slot) {
    --handles_held_;
    give_back(slot);
  }

 private:
  const Entry* front();  // the head entry of the current generation, stale ones given back
  NextEntry describe(const Entry* e, size_t i) const;

  Parts parts_;
  SpscRing<Entry> entries_;     // reader -> consumer
  SpscRing<uint32_t> returns_;  // consumer -> reader
  std::atomic<uint32_t> consumer_wake_{0};  // bumped whenever an entry is pushed

  // The consumer's alone.
  PlaybackSchedule schedule_;
  uint64_t generation_ = 0;
  uint64_t next_sequence_ = 0;
  uint32_t handles_held_ = 0;  // taken and not released
};

}  // namespace sluice::runtime::detail
