#include "sluice/render/staging_allocator.h"

#include <algorithm>
#include <cstdlib>
#include <new>
#include <stdexcept>
#include <thread>

#include "sluice/runtime/pipeline.h"

#include "staging_block.h"
#include "sluice/error.h"

namespace sluice::render {
namespace {

constexpr uint64_t kAlignment = 256;  // above every minStorageBufferOffsetAlignment and copy alignment

constexpr auto kStagingProps = vk::MemoryPropertyFlagBits::eHostVisible | vk::MemoryPropertyFlagBits::eHostCoherent;

}  // namespace

// What the frame slots may use of the staging heap. With
// VK_EXT_memory_budget: the heap's free bytes plus the staging blocks this
// allocator holds there (host fallbacks live elsewhere and do not count).
// Without it nothing is known about other users: the heap's size, which
// already includes what this allocator holds (adding it again made the plan
// grow with the window).
// With a resident window the same for the device-local heap and the areas
// held there.
class StagingAllocator::HeapBudget final : public runtime::DeviceMemoryBudget {
 public:
  HeapBudget(const Context& context, const StagingAllocator& owner, uint32_t heap, bool resident)
      : context_(context), owner_(owner), heap_(heap), resident_(resident) {}
  uint64_t available_bytes() const override {
    if (!context_impl(context_).memory_budget) return context_.heap_available_bytes(heap_);
    const uint64_t in_heap = resident_ ? owner_.resident_pool_->held_bytes()
                                       : owner_.pool_->held_where([](const StagingBlock& m) { return !m.host; });
    return context_.heap_available_bytes(heap_) + in_heap;
  }

 private:
  const Context& context_;
  const StagingAllocator& owner_;
  uint32_t heap_;
  bool resident_;
};

namespace {

// The resident area of buffers this allocator handed out (the ring's AreaOf).
ResidentArea& resident_area_of(const runtime::FrameBuffers& frame) { return *staging_memory_of(frame).area; }

uint32_t heap_with(const detail::ContextImpl& c, vk::MemoryPropertyFlags props) {
  for (uint32_t t = 0; t < c.memory.memoryTypeCount; ++t) {
    if ((c.memory.memoryTypes[t].propertyFlags & props) == props) return c.memory.memoryTypes[t].heapIndex;
  }
  return 0;
}

// The pipeline's read threads by default on this machine (one piece each
// at a time), and a few more so that a slot whose copy is still running
// is not waited for.
uint32_t default_ring_slots() {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return static_cast<uint32_t>(runtime::default_thread_split(cores, runtime::DecodeMode::KeepEncoded).read + 4);
}

}  // namespace

StagingAllocator::StagingAllocator(Context& context, const StagingOptions& options)
    : context_(context),
      options_(options),
      pool_(std::make_unique<StagingPool>()),
      resident_pool_(std::make_unique<StagingPool>()) {
  const detail::ContextImpl& c = context_impl(context);
  heap_ = heap_with(c, kStagingProps);
  device_heap_ = bool(c.memory.memoryHeaps[heap_].flags & vk::MemoryHeapFlagBits::eDeviceLocal);
  device_local_heap_ = heap_with(c, vk::MemoryPropertyFlagBits::eDeviceLocal);
  if (options_.resident) {
    const uint32_t slots = options_.ring_slots > 0 ? options_.ring_slots : default_ring_slots();
    ring_ = std::make_unique<RelayRing>(c, slots, std::max<uint64_t>(options_.ring_piece_bytes, 4096),
                                        options_.ring_memory == RingMemory::Imported, resident_area_of);
    budget_ = std::make_unique<HeapBudget>(context, *this, device_local_heap_, true);
  } else if (device_heap_) {
    budget_ = std::make_unique<HeapBudget>(context, *this, heap_, false);
  }
}

runtime::PieceRelay* StagingAllocator::relay() { return ring_.get(); }
uint32_t StagingAllocator::ring_slots() const { return ring_ ? ring_->slots() : 0; }
uint64_t StagingAllocator::ring_piece_bytes() const { return ring_ ? ring_->piece_bytes() : 0; }
bool StagingAllocator::ring_imported() const { return ring_ && ring_->imported(); }

VkSemaphore StagingAllocator::relay_semaphore() const { return ring_ ? static_cast<VkSemaphore>(ring_->semaphore()) : VK_NULL_HANDLE; }

StagingAllocator::~StagingAllocator() = default;

const runtime::DeviceMemoryBudget* StagingAllocator::device_budget() const { return budget_.get(); }

uint64_t StagingAllocator::kept_bytes() const { return pool_->kept_bytes() + resident_pool_->kept_bytes(); }
void StagingAllocator::trim(uint64_t keep) {
  // Host staging first: the window's frames are of one kind at a time.
  const uint64_t resident = resident_pool_->kept_bytes();
  pool_->trim(keep > resident ? keep - resident : 0);
  resident_pool_->trim(keep > pool_->kept_bytes() ? keep - pool_->kept_bytes() : 0);
}
uint64_t StagingAllocator::held_bytes() const { return pool_->held_bytes() + resident_pool_->held_bytes(); }
uint64_t StagingAllocator::peak_held_bytes() const { return pool_->peak_held_bytes() + resident_pool_->peak_held_bytes(); }
uint64_t StagingAllocator::fresh_allocations() const { return pool_->allocations() + resident_pool_->allocations(); }

namespace {
uint64_t resident_bytes(const runtime::FrameLayout& layout) { return (layout.encoded_bytes + kAlignment - 1) / kAlignment * kAlignment; }
}  // namespace

uint64_t StagingAllocator::bytes_for(const runtime::FrameLayout& layout) const {
  if (layout.resident) return resident_bytes(layout);
  return runtime::block_layout(layout, kAlignment).bytes;
}

runtime::FrameBuffers StagingAllocator::allocate(const runtime::FrameLayout& layout) {
  if (layout.resident) {
    if (!ring_) throw Error("StagingAllocator: a resident frame asked of an allocator without a resident window");
    const detail::ContextImpl& c = context_impl(context_);
    StagingPool::Block& block = resident_pool_->acquire(resident_bytes(layout), [&](uint64_t need) {
      StagingBlock m;
      m.area = std::make_unique<ResidentArea>(
          *ring_, create_buffer(c, need,
                                vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                                    vk::BufferUsageFlagBits::eTransferDst,
                                MemoryKind::DeviceLocal));
      return m;
    });
    // A read cut short may have left copies into it in flight.
    ring_->wait(block.memory.area->relayed.load(std::memory_order_relaxed));
    runtime::FrameBuffers out;
    out.tag = reinterpret_cast<uintptr_t>(&block);
    return out;
  }
  const runtime::BlockLayout at = runtime::block_layout(layout, kAlignment);
  StagingPool::Block& block = pool_->acquire(at.bytes, [&](uint64_t need) {
    StagingBlock m;
    try {
      // Encoded frames are read into the block and their checksums read back.
      m.staging = create_buffer(context_impl(context_), need, vk::BufferUsageFlagBits::eTransferSrc,
                                layout.encoded_bytes > 0 ? MemoryKind::UploadRead : MemoryKind::Upload);
    } catch (const vk::SystemError&) {
      // The driver has no more host-visible memory for us: plain host memory,
      // copied through the renderer's staging at upload.
      m.host.reset(static_cast<std::byte*>(std::aligned_alloc(kAlignment, need)));
      if (!m.host) throw std::bad_alloc();
      fallbacks_.fetch_add(1, std::memory_order_relaxed);
    }
    return m;
  });
  block.memory.attribute_offset = at.attribute_offset;
  block.memory.attribute_stride = at.attribute_stride;
  return runtime::lay_out_frame(block.memory.data(), layout, at, reinterpret_cast<uintptr_t>(&block));
}

void StagingAllocator::release(runtime::FrameBuffers& buffers) {
  if (!buffers.tag) return;
  StagingPool::Block& block = *reinterpret_cast<StagingPool::Block*>(static_cast<uintptr_t>(buffers.tag));
  (block.memory.resident() ? *resident_pool_ : *pool_).release(block);
  buffers = {};
}

FrameUpload frame_upload(const runtime::FrameHandle& frame, int color_attribute, const StagingAllocator* from) {
  if (frame.empty() || frame.failed()) throw Error("commit: an empty or failed frame handle");
  if (frame.content() == runtime::FrameContent::World) {
    throw Error(
        "commit: a frame converted to world units (DecodeMode::World) is for array consumers, not the renderer");
  }
  const runtime::FrameBuffers& buffers = frame.buffers();
  const StagingBlock* block = from ? &staging_memory(buffers) : nullptr;
  const bool vulkan = block && !block->host;  // else a host fallback: copied through the renderer's staging
  FrameUpload u;
  u.header = &frame.header();
  u.chunk_first = frame.chunk_first();
  u.particles.host = buffers.particles;
  if (vulkan && !block->resident()) u.particles.buffer = *block->staging.buffer;
  if (const io::GpuDecodePlan* plan = frame.gpu_plan()) {
    u.plan = plan;
    u.color_attribute = color_attribute;
    if (vulkan && block->resident()) {
      const ResidentArea& area = *block->area;
      u.particles = {};
      u.resident = {*area.device.buffer, area.device.address, area.device.size, from->relay_semaphore(),
                    area.relayed.load(std::memory_order_relaxed)};
    }
    return u;
  }
  // The streams hold every attribute (stream k is attribute k) or only the colour one.
  const size_t streams = buffers.attributes.size();
  const int stream = color_attribute < 0 ? -1 : streams == 1 ? 0 : color_attribute;
  if (stream >= 0 && size_t(stream) >= streams) {
    throw Error("commit: the frame holds " + std::to_string(streams) + " attribute streams, none of them attribute " +
                std::to_string(color_attribute));
  }
  if (stream >= 0) {
    const auto& values = buffers.attributes[size_t(stream)];
    u.color.host = std::as_bytes(std::span(values.data(), values.size()));
    u.color_attribute = color_attribute;
    if (vulkan) {
      u.color.buffer = *block->staging.buffer;
      u.color.offset = block->attribute_offset + uint64_t(stream) * block->attribute_stride;
    }
  }
  return u;
}

}  // namespace sluice::render
