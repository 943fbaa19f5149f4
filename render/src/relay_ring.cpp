#include "relay_ring.h"

#include <sys/mman.h>

#include <algorithm>
#include <stdexcept>

#include "sluice/error.h"

namespace sluice::render {

void RelayRing::Unmap::operator()(void* p) const { ::munmap(p, bytes); }

RelayRing::RelayRing(const detail::ContextImpl& ctx, uint32_t slots, uint64_t piece_bytes, bool import, AreaOf area_of)
    : ctx_(ctx), area_of_(area_of), piece_bytes_(piece_bytes), slots_(slots) {
  const uint64_t bytes = uint64_t(slots) * piece_bytes;
  const uint64_t align = import ? host_import_alignment(ctx) : 0;  // 0: the device cannot import
  if (align > 0) {
    const uint64_t rounded = (bytes + align - 1) / align * align;
    // Pages populated now, as the driver's memory would be.
    void* p = ::mmap(nullptr, rounded, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0);
    if (p != MAP_FAILED) {
      host_ = std::unique_ptr<void, Unmap>(p, Unmap{rounded});
      try {
        memory_ = import_host_buffer(ctx, p, rounded, vk::BufferUsageFlagBits::eTransferSrc);
      } catch (const vk::SystemError&) {
        memory_ = {};  // refused: the driver's memory below
      }
      if (memory_.mapped == nullptr) host_.reset();
    }
  }
  if (memory_.mapped == nullptr) {
    memory_ = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::UploadRead);
  }
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

ResidentArea::~ResidentArea() { ring.settle(*this); }

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
  for (;;) {
    std::unique_lock lock(mutex_);
    freed_.wait(lock, [&] { return !free_.empty() || !held_.empty(); });
    if (!free_.empty()) {
      s = free_.front();
      free_.pop_front();
      break;
    }
    // Every slot is sent or held back: the oldest held batch goes now.
    Batch batch = take(*held_.front());
    lock.unlock();
    submit(batch);
  }
  wait(slots_[s].ticket);  // its previous copy, if still running
  return {static_cast<std::byte*>(memory_.mapped) + s * piece_bytes_, bytes};
}

RelayRing::Batch RelayRing::take(ResidentArea& area) {
  Batch batch;
  if (area.held_slots.empty()) return batch;
  batch.area = &area;
  batch.copies.swap(area.held);
  batch.slots.swap(area.held_slots);
  std::erase(held_, &area);
  ++area.submitting;
  return batch;
}

void RelayRing::submit(Batch& batch) {
  ResidentArea& area = *batch.area;
  // The batch's first slot lends its command buffer: the submission that
  // last used it also held that slot, and claim() waited for it.
  const vk::CommandBuffer cmd = *slots_[batch.slots.front()].cmd;
  try {
    cmd.reset();
    cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    if (!batch.copies.empty()) cmd.copyBuffer(*memory_.buffer, *area.device.buffer, batch.copies);
    cmd.end();
    const vk::CommandBufferSubmitInfo cb(cmd);
    const std::lock_guard lock(mutex_);
    const uint64_t value = submitted_ + 1;
    const vk::SemaphoreSubmitInfo signal(*done_, value, vk::PipelineStageFlagBits2::eAllCommands);
    // Values must rise in submission order: submitted under mutex_.
    ctx_.submit(ctx_.relay_queue, vk::SubmitInfo2({}, {}, cb, signal));
    submitted_ = value;
    for (const uint32_t s : batch.slots) {
      slots_[s].ticket = value;
      free_.push_back(s);
    }
    area.relayed.store(std::max(area.relayed.load(std::memory_order_relaxed), value), std::memory_order_relaxed);
    --area.submitting;
  } catch (const vk::SystemError& e) {
    {
      const std::lock_guard lock(mutex_);
      for (const uint32_t s : batch.slots) free_.push_back(s);
      --area.submitting;
    }
    freed_.notify_all();
    submitted_cv_.notify_all();
    throw Error(std::string("relaying pieces to the GPU failed: ") + e.what());
  }
  freed_.notify_all();
  submitted_cv_.notify_all();
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
  ResidentArea& area = area_of_(frame);
  for (const Range& r : ranges) {
    if (r.from + r.bytes > piece.size() || r.to + r.bytes > area.device.size) {
      put_back(s);
      throw Error("RelayRing::send: a range outside the piece or the frame's area");
    }
  }
  const uint64_t base = uint64_t(s) * piece_bytes_;
  {
    const std::lock_guard lock(mutex_);
    if (area.held_slots.empty()) held_.push_back(&area);
    for (const Range& r : ranges) {
      if (r.bytes > 0) area.held.emplace_back(base + r.from, r.to, r.bytes);
    }
    area.held_slots.push_back(s);
  }
  freed_.notify_all();  // a claim waiting for a slot may submit this batch
}

void RelayRing::flush(const runtime::FrameBuffers& frame) {
  ResidentArea& area = area_of_(frame);
  std::unique_lock lock(mutex_);
  Batch batch = take(area);
  if (batch.area != nullptr) {
    lock.unlock();
    submit(batch);
    lock.lock();
  }
  // A claim on another thread may be submitting an earlier batch of it.
  submitted_cv_.wait(lock, [&] { return area.submitting == 0; });
}

void RelayRing::settle(ResidentArea& area) {
  bool freed = false;
  {
    std::unique_lock lock(mutex_);
    freed = !area.held_slots.empty();
    for (const uint32_t s : area.held_slots) free_.push_back(s);  // their previous copies were waited for in claim()
    area.held.clear();
    area.held_slots.clear();
    std::erase(held_, &area);
    submitted_cv_.wait(lock, [&] { return area.submitting == 0; });
  }
  if (freed) freed_.notify_all();
  wait(area.relayed.load(std::memory_order_relaxed));
}

}  // namespace sluice::render
