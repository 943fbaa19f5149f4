#include "relay_ring.h"

#include <stdexcept>

#include "staging_block.h"
#include "sluice/render/error.h"

namespace sluice::render {

RelayRing::RelayRing(const detail::ContextImpl& ctx, uint32_t slots, uint64_t piece_bytes)
    : ctx_(ctx), piece_bytes_(piece_bytes), slots_(slots) {
  memory_ = create_buffer(ctx, uint64_t(slots) * piece_bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::UploadRead);
  const uint32_t family = ctx.transfer_family;  // the relay queue's
  for (uint32_t s = 0; s < slots; ++s) {
    Slot& slot = slots_[s];
    slot.pool = vk::raii::CommandPool(ctx.device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, family));
    slot.cmd = std::move(vk::raii::CommandBuffers(ctx.device, vk::CommandBufferAllocateInfo(*slot.pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
    free_.push_back(s);
  }
  const vk::SemaphoreTypeCreateInfo timeline(vk::SemaphoreType::eTimeline, 0);
  done_ = vk::raii::Semaphore(ctx.device, vk::SemaphoreCreateInfo({}, &timeline));
}

ResidentArea::~ResidentArea() { ring.wait(relayed.load(std::memory_order_relaxed)); }

RelayRing::~RelayRing() {
  wait_all();
  // As in ~Renderer: lavapipe's queue thread still touches the timeline
  // after the host saw its value, so the queue goes idle before the
  // semaphore and the command buffers are destroyed.
  bool submitted = false;
  {
    const std::lock_guard lock(mutex_);
    submitted = submitted_ > 0;
  }
  if (submitted) ctx_.wait_idle(ctx_.relay_queue);
}

void RelayRing::wait(uint64_t value) const {
  if (value == 0) return;
  {
    const std::lock_guard lock(mutex_);
    if (broken_ && value > submitted_) return;  // its submission failed: it is never signalled
  }
  const vk::Semaphore sem = *done_;
  const vk::SemaphoreWaitInfo info({}, sem, value);
  while (ctx_.device.waitSemaphores(info, UINT64_MAX) == vk::Result::eTimeout) {
  }
}

void RelayRing::wait_all() const {
  uint64_t last = 0;
  {
    const std::lock_guard lock(mutex_);
    last = submitted_;
  }
  wait(last);
}

std::span<std::byte> RelayRing::claim(uint64_t bytes) {
  if (bytes > piece_bytes_) throw Error("RelayRing::claim: a piece larger than a slot");
  uint32_t s = 0;
  {
    std::unique_lock lock(mutex_);
    freed_.wait(lock, [&] { return !free_.empty(); });
    s = free_.front();
    free_.pop_front();
  }
  wait(slots_[s].ticket);  // its previous copy, if still running
  return {static_cast<std::byte*>(memory_.mapped) + s * piece_bytes_, bytes};
}

uint32_t RelayRing::slot_of(std::span<std::byte> piece) const {
  return static_cast<uint32_t>((piece.data() - static_cast<const std::byte*>(memory_.mapped)) / ptrdiff_t(piece_bytes_));
}

void RelayRing::put_back(uint32_t slot) {
  {
    const std::lock_guard lock(mutex_);
    free_.push_back(slot);
  }
  freed_.notify_one();
}

void RelayRing::give_back(std::span<std::byte> piece) { put_back(slot_of(piece)); }

void RelayRing::send(std::span<std::byte> piece, const runtime::FrameBuffers& frame, std::span<const Range> ranges) {
  const uint32_t s = slot_of(piece);
  Slot& slot = slots_[s];
  ResidentArea& area = *staging_memory_of(frame).area;
  try {
    thread_local std::vector<vk::BufferCopy> regions;
    regions.clear();
    const uint64_t base = uint64_t(s) * piece_bytes_;
    for (const Range& r : ranges) {
      if (r.from + r.bytes > piece.size() || r.to + r.bytes > area.device.size) {
        throw Error("RelayRing::send: a range outside the piece or the frame's area");
      }
      if (r.bytes > 0) regions.emplace_back(base + r.from, r.to, r.bytes);
    }
    vk::CommandBuffer cmd = *slot.cmd;
    cmd.reset();
    cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    if (!regions.empty()) cmd.copyBuffer(*memory_.buffer, *area.device.buffer, regions);
    cmd.end();
  } catch (const vk::SystemError& e) {
    put_back(s);
    throw Error(std::string("relaying a piece to the GPU failed: ") + e.what());
  } catch (...) {
    put_back(s);
    throw;
  }
  uint64_t value = 0;
  {
    const std::lock_guard lock(mutex_);
    value = ++assigned_;
    slot.ticket = value;
    queued_.push_back(s);
  }
  // The area's decode waits for its newest copy (several threads send into one area).
  uint64_t seen = area.relayed.load(std::memory_order_relaxed);
  while (seen < value && !area.relayed.compare_exchange_weak(seen, value, std::memory_order_relaxed)) {
  }
  submit_until(value);
}

// Waits, or submits, until `value`'s copy is submitted: a consumer that waits
// for it on the GPU is submitted after it (on a queue shared with the relay,
// a wait for a signal not yet submitted would stall the queue for good).
void RelayRing::submit_until(uint64_t value) {
  thread_local std::vector<uint32_t> batch;
  thread_local std::vector<vk::CommandBufferSubmitInfo> buffers;
  std::unique_lock lock(mutex_);
  while (submitted_ < value) {
    if (broken_) throw Error("relaying a piece to the GPU failed: an earlier submission of the relay failed");
    if (submitting_) {  // that thread takes our copy along
      submitted_now_.wait(lock);
      continue;
    }
    submitting_ = true;
    batch.swap(queued_);
    queued_.clear();
    const uint64_t newest = assigned_;  // the newest queued copy's: values rise in queue order
    lock.unlock();
    buffers.clear();
    for (uint32_t s : batch) buffers.emplace_back(*slots_[s].cmd);
    const vk::SemaphoreSubmitInfo signal(*done_, newest, vk::PipelineStageFlagBits2::eAllCommands);
    bool failed = false;
    std::string why;
    try {
      ctx_.submit(ctx_.relay_queue, vk::SubmitInfo2({}, {}, buffers, signal));
    } catch (const vk::SystemError& e) {
      failed = true;
      why = e.what();
    }
    lock.lock();
    submitting_ = false;
    if (failed) {
      broken_ = true;
      for (uint32_t s : batch) slots_[s].ticket = 0;  // never signalled: claim() must not wait for it
    } else {
      submitted_ = newest;
    }
    for (uint32_t s : batch) free_.push_back(s);
    freed_.notify_all();
    submitted_now_.notify_all();
    if (failed) throw Error("relaying a piece to the GPU failed: " + why);
  }
}

}  // namespace sluice::render
