#include "delivery.h"

#include <exception>
#include <string>

#include "slot_window.h"
#include "sluice/error.h"

namespace sluice::runtime::detail {
namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

}  // namespace

Delivery::Delivery(const Parts& parts) : parts_(parts), entries_(parts.slot_count), returns_(parts.slot_count) {}

void Delivery::publish(const Entry& entry) {
  // The window never holds more entries than the ring: a push cannot fail.
  if (!entries_.try_push(entry)) std::terminate();
  wake_consumer();
}

void Delivery::begin(const PlaybackSchedule& schedule, uint64_t generation) {
  schedule_ = schedule;
  generation_ = generation;
  next_sequence_ = 0;
  front();  // gives back what is queued of older generations
}

void Delivery::give_back(uint32_t s) {
  // The return ring holds every slot at once: a push cannot fail.
  if (!returns_.try_push(s)) std::terminate();
  wake(*parts_.reader_wake);
}

const Entry* Delivery::front() {
  // Entries of older generations form a prefix of the ring: the reader may
  // still push one it was working on when restart() came. Drop them here,
  // checking the very entry returned, so a late arrival is never mistaken
  // for the current generation's.
  while (const Entry* e = entries_.peek(0)) {
    if (e->generation == generation_) return e;
    Entry gone;
    entries_.try_pop(gone);
    parts_.slots[gone.slot].abandoned.store(true, std::memory_order_release);
    give_back(gone.slot);
  }
  return nullptr;
}

NextEntry Delivery::describe(const Entry* e, size_t i) const {
  NextEntry n;
  n.sequence = next_sequence_ + i;
  if (!e) {
    const auto frame = schedule_.frame_at(n.sequence);
    n.end = !frame || parts_.reader_failed->load(std::memory_order_acquire);
    n.frame = frame.value_or(0);
    return n;
  }
  n.frame = e->frame;
  switch (parts_.slots[e->slot].state.load(std::memory_order_acquire)) {
    case SlotState::Ready: n.status = EntryStatus::Ready; break;
    case SlotState::Failed: n.status = EntryStatus::Failed; break;
    default: n.status = EntryStatus::Pending; break;
  }
  return n;
}

NextEntry Delivery::peek(size_t i) {
  // Behind a current head every entry is current.
  return describe(front() ? entries_.peek(i) : nullptr, i);
}

NextEntry Delivery::wait_next() {
  while (true) {
    const uint32_t seen = consumer_wake_.load(std::memory_order_acquire);
    const Entry* e = front();
    if (!e) {
      const NextEntry n = describe(nullptr, 0);
      if (n.end) return n;
      // The reader starts no frame while the consumer's handles fill what it
      // may keep ahead: waiting would never end.
      const uint32_t window = parts_.counters->window_frames.load(kRelaxed);
      if (handles_held_ >= ahead_most(window)) {
        throw Error("Pipeline::wait_next(): the consumer holds " + std::to_string(handles_held_) +
                    " frames, all the reader may keep ahead in a window of " + std::to_string(window) +
                    ": release one (FrameHandle::reset) before waiting for the next");
      }
      consumer_wake_.wait(seen, std::memory_order_acquire);
      continue;
    }
    const SlotState state = parts_.slots[e->slot].state.load(std::memory_order_acquire);
    if (state == SlotState::Ready || state == SlotState::Failed) return describe(e, 0);
    parts_.slots[e->slot].state.wait(state, std::memory_order_acquire);
  }
}

Delivery::Taken Delivery::take() {
  const Entry* e = front();
  const SlotState state = e ? parts_.slots[e->slot].state.load(std::memory_order_acquire) : SlotState::Free;
  if (state != SlotState::Ready && state != SlotState::Failed) {
    throw Error("Pipeline::take(): the next entry is not ready (check peek() or wait_next() first)");
  }
  Taken taken;
  entries_.try_pop(taken.entry);
  taken.state = state;
  ++next_sequence_;
  return taken;
}

void Delivery::drop() {
  Entry entry;
  if (!front() || !entries_.try_pop(entry)) throw Error("Pipeline::drop(): no entry to drop");
  ++next_sequence_;
  parts_.slots[entry.slot].abandoned.store(true, std::memory_order_release);
  give_back(entry.slot);
}

uint32_t Delivery::ready_count() {
  uint32_t ready = 0;
  for (size_t i = 0; const Entry* e = front() ? entries_.peek(i) : nullptr; ++i) {
    if (parts_.slots[e->slot].state.load(std::memory_order_acquire) == SlotState::Ready) ++ready;
  }
  parts_.counters->frames_ready.store(ready, kRelaxed);
  return ready;
}

}  // namespace sluice::runtime::detail
