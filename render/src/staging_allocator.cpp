#include "sluice/render/staging_allocator.h"

#include <algorithm>
#include <cstdlib>
#include <new>

#include "staging_block.h"

namespace sluice::render {
namespace {

constexpr uint64_t kAlignment = 256;  // above every minStorageBufferOffsetAlignment and copy alignment

uint64_t align_up(uint64_t n) { return (n + kAlignment - 1) / kAlignment * kAlignment; }

constexpr auto kStagingProps = vk::MemoryPropertyFlagBits::eHostVisible | vk::MemoryPropertyFlagBits::eHostCoherent;

}  // namespace

StagingAllocator::Block::~Block() { std::free(host); }

// Free bytes of the staging heap, plus what the allocator holds there.
class StagingAllocator::HeapBudget final : public runtime::DeviceMemoryBudget {
 public:
  HeapBudget(const Context& context, const StagingAllocator& owner, uint32_t heap)
      : context_(context), owner_(owner), heap_(heap) {}
  uint64_t available_bytes() const override {
    return context_.heap_available_bytes(heap_) + owner_.held_bytes();
  }

 private:
  const Context& context_;
  const StagingAllocator& owner_;
  uint32_t heap_;
};

StagingAllocator::StagingAllocator(Context& context) : context_(context) {
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

void StagingAllocator::account(int64_t delta) {
  const uint64_t now = held_.fetch_add(uint64_t(delta), std::memory_order_relaxed) + uint64_t(delta);
  uint64_t peak = peak_.load(std::memory_order_relaxed);
  while (now > peak && !peak_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
  }
}

uint64_t StagingAllocator::bytes_for(const runtime::FrameLayout& layout) const {
  return std::max(kAlignment, align_up(layout.particle_bytes()) + layout.attribute_streams * align_up(layout.attribute_bytes()));
}

runtime::FrameBuffers StagingAllocator::allocate(const runtime::FrameLayout& layout) {
  const uint64_t need = bytes_for(layout);
  // Reuse the smallest kept block that fits; if none does, free one kept block
  // first so that the number of blocks never exceeds the most used at once.
  auto fits = kept_.end();
  for (auto it = kept_.begin(); it != kept_.end(); ++it) {
    if ((*it)->capacity >= need && (fits == kept_.end() || (*it)->capacity < (*fits)->capacity)) fits = it;
  }
  Block* block = nullptr;
  if (fits != kept_.end()) {
    block = *fits;
    kept_.erase(fits);
  } else {
    if (!kept_.empty()) {
      block = kept_.back();
      kept_.pop_back();
      account(-int64_t(block->capacity));
      block->staging = Buffer{};
      std::free(block->host);
      block->host = nullptr;
      block->capacity = 0;
    } else {
      blocks_.push_back(std::make_unique<Block>());
      block = blocks_.back().get();
    }
    try {
      block->staging = create_buffer(context_impl(context_), need, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
    } catch (const vk::SystemError&) {
      // The driver has no more host-visible memory for us: plain host memory,
      // copied through the renderer's staging at upload.
      block->staging = Buffer{};
      block->host = static_cast<std::byte*>(std::aligned_alloc(kAlignment, need));
      if (!block->host) {
        kept_.push_back(block);  // empty, reusable, costs nothing
        throw std::bad_alloc();
      }
      fallbacks_.fetch_add(1, std::memory_order_relaxed);
    }
    block->capacity = need;
    account(int64_t(need));
  }
  block->in_use = true;
  block->attribute_offset = align_up(layout.particle_bytes());
  block->attribute_stride = align_up(layout.attribute_bytes());

  runtime::FrameBuffers out;
  out.tag = reinterpret_cast<uintptr_t>(block);
  std::byte* base = block->data();
  out.particles = {base, layout.particle_bytes()};
  for (uint32_t s = 0; s < layout.attribute_streams; ++s) {
    out.attributes.emplace_back(reinterpret_cast<uint16_t*>(base + block->attribute_offset + s * block->attribute_stride),
                                layout.particles);
  }
  return out;
}

void StagingAllocator::release(runtime::FrameBuffers& buffers) {
  Block* block = reinterpret_cast<Block*>(static_cast<uintptr_t>(buffers.tag));
  if (!block || !block->in_use) return;
  block->in_use = false;
  kept_.push_back(block);
  buffers = {};
}

}  // namespace sluice::render
