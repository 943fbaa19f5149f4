#include "slot_window.h"

#include <algorithm>

#include "sluice/runtime/budget.h"

namespace sluice::runtime::detail {
namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

// Small moves of the window are noise (MemAvailable wobbles); follow a
// change only when it is worth an eighth of the window.
bool worth_changing(uint32_t from, uint32_t to) {
  const uint32_t margin = from / 8;
  return to + margin < from || to > from + margin;
}

}  // namespace

WindowPlan SlotWindow::plan(const Parts& parts, uint64_t held) {
  const WindowSettings& o = *parts.options;
  BudgetReading reading;
  reading.host = read_host_memory(o.budget.host_paths);
  reading.held_bytes = held;
  if (o.device_budget) reading.device_available = o.device_budget->available_bytes();
  WindowPlan plan = plan_window(parts.footprint, reading, o.budget, parts.decode_threads);
  // More slots than frames would hold copies of the same frames (a short
  // loop); with one slot per frame a loop is read once and then served from
  // memory.
  const auto frames = static_cast<uint32_t>(std::min<uint64_t>(parts.file_frames, plan.frames));
  if (frames < plan.frames) {
    plan.frames = std::max<uint32_t>(2, frames);
    plan.record_buffers = std::min(plan.record_buffers, plan.frames);
    plan.limited_by = "frames in the file";
  }
  return plan;
}

uint32_t SlotWindow::initial_active(const Parts& parts, const WindowPlan& plan) {
  if (!parts.options->slow_start) return plan.frames;
  return std::min<uint32_t>(plan.frames, static_cast<uint32_t>(std::max(4, parts.decode_threads + 2)));
}

SlotWindow::SlotWindow(const Parts& parts, const WindowPlan& initial)
    : parts_(parts), plan_(initial), active_(initial_active(parts, initial)),
      next_evaluation_(parts.options->reevaluate_every) {
  // Every list a slot count long at most: reserved once, so the frame path
  // never allocates.
  free_slots_.reserve(parts.slot_count);
  cached_.reserve(parts.slot_count);
  draining_.reserve(parts.slot_count);
  for (uint32_t s = parts.slot_count; s-- > 0;) free_slots_.push_back(s);
  for (auto r = static_cast<uint32_t>(parts.records->size()); r-- > 0;) free_records_.push_back(r);
}

uint32_t SlotWindow::occupied(uint32_t in_flight) const {
  return in_flight + static_cast<uint32_t>(cached_.size() + draining_.size());
}

bool SlotWindow::grow() {
  // Slow start: a fresh frame buffer costs a page fault per 4 KiB on first
  // use, and a window whose buffers are all fresh makes every frame pay it.
  // So the window starts small (its buffers are soon reused) and grows only
  // while the reader is ahead of the consumer and decoding is idle: when a
  // deeper prefetch is both useful and free.
  if (active_ >= plan_.frames || parts_.frames_decoding->load(std::memory_order_acquire) > 0) return false;
  ++active_;
  parts_.counters->active_frames.store(active_, kRelaxed);
  return true;
}

void SlotWindow::reevaluate_if_due() {
  if (frames_started_ < next_evaluation_) return;
  const WindowSettings& o = *parts_.options;
  next_evaluation_ = frames_started_ + std::max<uint32_t>(1, o.reevaluate_every);
  const WindowPlan next = plan(parts_, held());
  if (!worth_changing(plan_.frames, next.frames)) return;
  const uint32_t previous = plan_.frames;
  plan_ = next;
  active_ = o.slow_start ? std::min(active_, next.frames) : next.frames;
  Counters& c = *parts_.counters;
  c.active_frames.store(active_, kRelaxed);
  c.window_frames.store(next.frames, kRelaxed);
  c.record_buffers.store(next.record_buffers, kRelaxed);
  if (o.on_change) o.on_change({previous, next});
}

void SlotWindow::shrink(uint32_t in_flight, uint32_t unbuffered) {
  while (occupied(in_flight) > active_ && evict_oldest()) {
  }
  // Memory held follows the window: kept buffers beyond the free slots'
  // worth go back (steady playback never has more, so nothing is freed).
  const uint64_t free_slots = (active_ > occupied(in_flight) ? active_ - occupied(in_flight) : 0) + unbuffered;
  const uint64_t keep = free_slots * parts_.footprint.decoded_bytes;
  if (parts_.allocator->kept_bytes() > keep) {
    parts_.allocator->trim(keep);
    publish_held();
  }
}

void SlotWindow::returned(uint32_t s) {
  const SlotState state = parts_.slots[s].state.load(std::memory_order_acquire);
  if (state == SlotState::Decoding) draining_.push_back(s);
  else settle(s, state);
}

void SlotWindow::settle_drained() {
  // Dropped work finishes quickly: its remaining chunks are skipped.
  std::erase_if(draining_, [&](uint32_t d) {
    const SlotState state = parts_.slots[d].state.load(std::memory_order_acquire);
    if (state == SlotState::Decoding) return false;
    settle(d, state);
    return true;
  });
}

void SlotWindow::settle(uint32_t s, SlotState state) {
  Slot& slot = parts_.slots[s];
  if ((state == SlotState::Ready || state == SlotState::Shown) && slot.has_buffers && !slot.spoiled) {
    slot.state.store(SlotState::Cached, kRelaxed);
    cached_.push_back(s);
  } else {
    free_slot(s);
  }
}

std::optional<uint32_t> SlotWindow::take_cached(uint64_t frame) {
  const auto hit = std::find_if(cached_.rbegin(), cached_.rend(), [&](uint32_t s) { return parts_.slots[s].frame == frame; });
  if (hit == cached_.rend()) return std::nullopt;
  const uint32_t s = *hit;
  cached_.erase(std::next(hit).base());
  return s;
}

std::optional<SlotWindow::Claim> SlotWindow::claim(uint32_t in_flight) {
  while (occupied(in_flight) >= active_ && evict_oldest()) {
  }
  if (occupied(in_flight) >= active_) return std::nullopt;
  const auto in_use = static_cast<uint32_t>(parts_.records->size() - free_records_.size());
  if (free_records_.empty() || in_use >= plan_.record_buffers) return std::nullopt;
  // Prefer a record buffer that already has memory.
  auto pick = std::find_if(free_records_.begin(), free_records_.end(),
                           [&](uint32_t r) { return (*parts_.records)[r].capacity() > 0; });
  if (pick == free_records_.end()) pick = free_records_.begin();
  const Claim claimed{free_slots_.back(), *pick};
  free_records_.erase(pick);
  free_slots_.pop_back();
  return claimed;
}

void SlotWindow::free_slot(uint32_t s) {
  Slot& slot = parts_.slots[s];
  release_buffers(slot);
  slot.state.store(SlotState::Free, kRelaxed);
  free_slots_.push_back(s);
}

bool SlotWindow::evict_oldest() {
  if (cached_.empty()) return false;
  const uint32_t s = cached_.front();
  cached_.erase(cached_.begin());
  free_slot(s);
  return true;
}

void SlotWindow::allocate_buffers(Slot& slot) {
  slot.buffers = parts_.allocator->allocate(slot.layout);
  slot.has_buffers = true;
  decoded_held_ += parts_.allocator->bytes_for(slot.layout);
  publish_held();
}

void SlotWindow::release_buffers(Slot& slot) {
  if (!slot.has_buffers) return;
  decoded_held_ -= parts_.allocator->bytes_for(slot.layout);
  parts_.allocator->release(slot.buffers);
  slot.has_buffers = false;
  publish_held();
}

void SlotWindow::replace_buffers(Slot& slot, const FrameLayout& layout, const FrameBuffers& buffers) {
  release_buffers(slot);
  slot.layout = layout;
  slot.buffers = buffers;
  slot.has_buffers = true;
  decoded_held_ += parts_.allocator->bytes_for(slot.layout);
  publish_held();
}

AlignedBuffer& SlotWindow::record_buffer(uint32_t record, uint64_t bytes) {
  AlignedBuffer& buffer = (*parts_.records)[record];
  const size_t before = buffer.capacity();
  buffer.reserve(bytes);
  if (buffer.capacity() != before) {
    record_held_ += buffer.capacity() - before;
    publish_held();
    Counters& c = *parts_.counters;
    if (record_held_ > c.peak_record_bytes.load(kRelaxed)) c.peak_record_bytes.store(record_held_, kRelaxed);
  }
  return buffer;
}

void SlotWindow::take_record_returns(MpscRing<uint32_t>& returns) {
  uint32_t r;
  while (returns.try_pop(r)) free_records_.push_back(r);
  // Give memory back when the plan allows fewer record buffers than we hold.
  std::vector<AlignedBuffer>& records = *parts_.records;
  auto allocated = std::count_if(records.begin(), records.end(), [](const AlignedBuffer& b) { return b.capacity() > 0; });
  for (uint32_t f : free_records_) {
    if (allocated <= plan_.record_buffers) break;
    if (records[f].capacity() == 0) continue;
    record_held_ -= records[f].capacity();
    records[f].release();
    --allocated;
  }
  publish_held();
}

uint64_t SlotWindow::held() const { return decoded_held_ + parts_.allocator->kept_bytes() + record_held_; }

void SlotWindow::publish_held() const { parts_.counters->held_bytes.store(held(), kRelaxed); }

}  // namespace sluice::runtime::detail
