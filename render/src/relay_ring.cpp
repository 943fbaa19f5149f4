#include "relay_ring.h"

#include <sys/mman.h>

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
  ResidentArea& area = area_of_(frame);
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
    const vk::CommandBufferSubmitInfo cb(cmd);
    std::unique_lock lock(mutex_);
    const uint64_t value = submitted_ + 1;
    const vk::SemaphoreSubmitInfo signal(*done_, value, vk::PipelineStageFlagBits2::eAllCommands);
    // Values must rise in submission order: submitted under mutex_.
    ctx_.submit(ctx_.relay_queue, vk::SubmitInfo2({}, {}, cb, signal));
    submitted_ = value;
    slot.ticket = value;
    free_.push_back(s);
    lock.unlock();
    freed_.notify_one();
    // The area's decode waits for its newest copy (several threads send into one area).
    uint64_t seen = area.relayed.load(std::memory_order_relaxed);
    while (seen < value && !area.relayed.compare_exchange_weak(seen, value, std::memory_order_relaxed)) {
    }
  } catch (const vk::SystemError& e) {
    put_back(s);
    throw Error(std::string("relaying a piece to the GPU failed: ") + e.what());
  } catch (...) {
    put_back(s);
    throw;
  }
}

}  // namespace sluice::render
