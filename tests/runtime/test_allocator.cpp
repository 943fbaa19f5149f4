// The accounting host allocator: sizes, alignment, reuse, and that what it
// holds never exceeds the most buffers in use at once.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "sluice/runtime/frame_allocator.h"

using namespace sluice::runtime;

namespace {

FrameLayout layout(uint64_t particles, uint32_t streams = 1) {
  FrameLayout l;
  l.particles = particles;
  l.particle_stride = 8;
  l.attribute_streams = streams;
  return l;
}

}  // namespace

TEST(HostFrameAllocator, HandsOutAlignedBuffersOfTheLayoutsSize) {
  HostFrameAllocator a;
  FrameBuffers b = a.allocate(layout(1001, 2));
  EXPECT_EQ(b.particles.size(), 8008u);
  ASSERT_EQ(b.attributes.size(), 2u);
  EXPECT_EQ(b.attributes[1].size(), 1001u);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(b.particles.data()) % 16, 0u);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(b.attributes[0].data()) % 16, 0u);
  EXPECT_GE(reinterpret_cast<std::byte*>(b.attributes[0].data()), b.particles.data() + b.particles.size());
  EXPECT_EQ(a.held_bytes(), a.bytes_for(layout(1001, 2)));
  EXPECT_GE(a.bytes_for(layout(1001, 2)), layout(1001, 2).total_bytes());
  a.release(b);
  EXPECT_EQ(a.in_use_buffers(), 0u);
}

TEST(HostFrameAllocator, ReusesReleasedBuffers) {
  HostFrameAllocator a;
  FrameBuffers b = a.allocate(layout(5000));
  const std::byte* first = b.particles.data();
  a.release(b);
  FrameBuffers c = a.allocate(layout(4000));  // fits in the kept block
  EXPECT_EQ(c.particles.data(), first);
  EXPECT_EQ(a.allocations(), 1u);
  a.release(c);
}

TEST(HostFrameAllocator, HoldsNoMoreThanTheMostInUseAtOnce) {
  HostFrameAllocator a;
  std::mt19937 rng(7);
  std::vector<FrameBuffers> live;
  uint64_t most_in_use = 0, largest = 0;
  for (int i = 0; i < 2000; ++i) {
    if (live.size() < 6 && (live.empty() || rng() % 2)) {
      const FrameLayout l = layout(1000 + rng() % 50000);
      largest = std::max(largest, a.bytes_for(l));
      live.push_back(a.allocate(l));
    } else {
      const size_t k = rng() % live.size();
      a.release(live[k]);
      live.erase(live.begin() + static_cast<long>(k));
    }
    most_in_use = std::max<uint64_t>(most_in_use, live.size());
    ASSERT_LE(a.held_bytes(), most_in_use * largest);
  }
  EXPECT_LE(a.peak_held_bytes(), 6 * largest);
  for (auto& b : live) a.release(b);
}

// trim() gives kept buffers back (largest first) down to what it is told to
// keep, never a buffer in use; emptied blocks are reused as shells.
TEST(HostFrameAllocator, TrimGivesKeptBuffersBack) {
  HostFrameAllocator a;
  std::vector<FrameBuffers> live;
  for (uint64_t i = 0; i < 8; ++i) live.push_back(a.allocate(layout(1000 * (i + 1))));
  const uint64_t one = a.bytes_for(layout(1000)), all = a.held_bytes();
  for (size_t i = 1; i < live.size(); ++i) a.release(live[i]);  // live[0] stays in use
  EXPECT_EQ(a.kept_bytes(), all - one);
  a.trim(3 * a.bytes_for(layout(3000)));
  EXPECT_LE(a.kept_bytes(), 3 * a.bytes_for(layout(3000)));
  EXPECT_EQ(a.held_bytes(), one + a.kept_bytes()) << "the buffer in use is untouched";
  EXPECT_NE(live[0].particles.data(), nullptr);
  a.trim(0);
  EXPECT_EQ(a.kept_bytes(), 0u);
  EXPECT_EQ(a.held_bytes(), one);
  // The window grows again: new buffers, in the blocks' old shells.
  for (size_t i = 1; i < live.size(); ++i) live[i] = a.allocate(layout(2000));
  EXPECT_EQ(a.held_bytes(), one + 7 * a.bytes_for(layout(2000)));
  EXPECT_EQ(a.in_use_buffers(), 8u);
  for (auto& b : live) a.release(b);
}
