// Internal: the ring a StagingAllocator with a resident window relays
// frames' pieces through (runtime/frame_allocator.h): slots of cached host-visible
// memory the read threads write with plain stores, each copied by the GPU
// into a frame's resident area on the context's relay queue right after.
// Every copy signals the ring's timeline semaphore with the next value; a
// slot is reused once its copy's value is reached, and the area remembers
// the largest value copied into it (what its decode waits for).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <vector>

#include "sluice/runtime/frame_allocator.h"
#include "vk_common.h"

namespace sluice::render {

class RelayRing;

// A frame's staged area in device memory, filled by the ring's copies.
// Destroying it waits for the copies into it (a read a newer schedule cut
// short may leave some in flight).
struct ResidentArea {
  ResidentArea(const RelayRing& relay, Buffer buffer) : ring(relay), device(std::move(buffer)) {}
  ~ResidentArea();
  ResidentArea(const ResidentArea&) = delete;
  ResidentArea& operator=(const ResidentArea&) = delete;
  const RelayRing& ring;
  Buffer device;
  std::atomic<uint64_t> relayed{0};  // the largest ring timeline value copied into it
};

class RelayRing final : public runtime::PieceRelay {
 public:
  // The resident area of a frame's buffers (their allocator knows it).
  using AreaOf = ResidentArea& (*)(const runtime::FrameBuffers& frame);
  // `slots` slots of `piece_bytes` each, in anonymous memory the device
  // imports when `import` and it can (imported()), else in the driver's.
  // Throws vk::SystemError when the memory cannot be had.
  RelayRing(const detail::ContextImpl& ctx, uint32_t slots, uint64_t piece_bytes, bool import, AreaOf area_of);
  ~RelayRing() override;  // waits for the copies in flight
  RelayRing(const RelayRing&) = delete;
  RelayRing& operator=(const RelayRing&) = delete;

  uint64_t piece_bytes() const override { return piece_bytes_; }
  std::span<std::byte> claim(uint64_t bytes) override;
  void send(std::span<std::byte> piece, const runtime::FrameBuffers& frame, std::span<const Range> ranges) override;
  void give_back(std::span<std::byte> piece) override;

  // The timeline the copies signal, and waiting on it (any thread).
  vk::Semaphore semaphore() const { return *done_; }
  void wait(uint64_t value) const;
  void wait_all() const;  // every copy submitted so far
  uint32_t slots() const { return static_cast<uint32_t>(slots_.size()); }
  bool imported() const { return host_ != nullptr; }

 private:
  struct Slot {
    vk::raii::CommandPool pool{nullptr};
    vk::raii::CommandBuffer cmd{nullptr};
    uint64_t ticket = 0;  // the value its last copy signals
  };
  uint32_t slot_of(std::span<std::byte> piece) const;
  void put_back(uint32_t slot);

  const detail::ContextImpl& ctx_;
  AreaOf area_of_;
  uint64_t piece_bytes_;
  // Host memory the ring's buffer imports, unmapped after memory_ is freed
  // (members go in reverse order); null when memory_ is the driver's own.
  struct Unmap {
    size_t bytes;  // no initializer: one makes a nested class not default-constructible inside RelayRing
    void operator()(void* p) const;
  };
  std::unique_ptr<void, Unmap> host_;
  Buffer memory_;  // slots() * piece_bytes_, cached host-visible, mapped
  std::vector<Slot> slots_;
  vk::raii::Semaphore done_{nullptr};
  mutable std::mutex mutex_;  // free_ and submitted_
  std::condition_variable freed_;
  std::deque<uint32_t> free_;  // oldest copy first
  uint64_t submitted_ = 0;     // the value the newest copy signals
};

}  // namespace sluice::render
