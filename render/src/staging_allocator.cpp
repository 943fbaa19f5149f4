#include "sluice/render/staging_allocator.h"

#include <algorithm>
#include <cstdlib>
#include <new>

#include "staging_block.h"

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
class StagingAllocator::HeapBudget final : public runtime::DeviceMemoryBudget {
 public:
  HeapBudget(const Context& context, const StagingAllocator& owner, uint32_t heap)
      : context_(context), owner_(owner), heap_(heap) {}
  uint64_t available_bytes() const override {
    if (!context_impl(context_).memory_budget) return context_.heap_available_bytes(heap_);
    const uint64_t in_heap = owner_.pool_->held_where([](const Memory& m) { return !m.host; });
    return context_.heap_available_bytes(heap_) + in_heap;
  }

 private:
  const Context& context_;
  const StagingAllocator& owner_;
  uint32_t heap_;
};

StagingAllocator::StagingAllocator(Context& context) : context_(context), pool_(std::make_unique<Pool>()) {
  const Context::Impl& c = context_impl(context);
  for (uint32_t t = 0; t < c.memory.memoryTypeCount; ++t) {
    if ((c.memory.memoryTypes[t].propertyFlags & kStagingProps) == kStagingProps) {
      heap_ = c.memory.memoryTypes[t].heapIndex;
      device_heap_ = bool(c.memory.memoryHeaps[heap_].flags & vk::MemoryHeapFlagBits::eDeviceLocal);
      break;
    }
  }
  if (device_heap_) budget_ = std::make_unique<HeapBudget>(context, *this, heap_);
}

StagingAllocator::~StagingAllocator() = default;

const runtime::DeviceMemoryBudget* StagingAllocator::device_budget() const { return budget_.get(); }

uint64_t StagingAllocator::kept_bytes() const { return pool_->kept_bytes(); }
void StagingAllocator::trim(uint64_t keep) { pool_->trim(keep); }
uint64_t StagingAllocator::held_bytes() const { return pool_->held_bytes(); }
uint64_t StagingAllocator::peak_held_bytes() const { return pool_->peak_held_bytes(); }
uint64_t StagingAllocator::fresh_allocations() const { return pool_->allocations(); }

uint64_t StagingAllocator::bytes_for(const runtime::FrameLayout& layout) const {
  return runtime::block_layout(layout, kAlignment).bytes;
}

runtime::FrameBuffers StagingAllocator::allocate(const runtime::FrameLayout& layout) {
  const runtime::BlockLayout at = runtime::block_layout(layout, kAlignment);
  Pool::Block& block = pool_->acquire(at.bytes, [&](uint64_t need) {
    Memory m;
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
  pool_->release(*reinterpret_cast<Pool::Block*>(static_cast<uintptr_t>(buffers.tag)));
  buffers = {};
}

}  // namespace sluice::render
