#include "sluice/runtime/budget.h"

#include <algorithm>
#include <limits>
#include <vector>

#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/reader.h"

namespace sluice::runtime {
namespace {

// Room to widen a record to O_DIRECT alignment at both ends (record buffers
// are whole 4 KiB pages).
constexpr uint64_t kAlignmentSlack = 2 * 4096;
// The host budget when neither /proc/meminfo nor a cgroup could be read.
constexpr uint64_t kFallbackHostBudget = uint64_t(1) << 30;

uint32_t clamp_frames(uint64_t frames) {
  return static_cast<uint32_t>(std::min<uint64_t>(frames, std::numeric_limits<uint32_t>::max()));
}

}  // namespace

FrameFootprint largest_frame(const io::ContainerReader& reader, size_t attribute_streams,
                             const FrameAllocator* allocator, io::LayerSet layers, bool encoded, uint32_t particle_stride) {
  FrameLayout layout;
  layout.particle_stride =
      particle_stride > 0 ? particle_stride : static_cast<uint32_t>(io::decoded_particle_bytes(reader.header().position_coding));
  layout.attribute_streams = static_cast<uint32_t>(attribute_streams);
  FrameFootprint f;
  for (const io::FrameIndexEntry& e : reader.index().frames) {
    layout.particles = e.count_in(layers);
    // The real plan is known once the record's tables are read; before, a
    // bound: every plane inflated on the CPU (n bytes each, rounded to 16),
    // the chunk plans and the tile table, the roundings and the padding.
    if (encoded) {
      const uint64_t n = layout.particles, chunks = e.chunk_count, planes = io::kGpuPlanes;
      layout.encoded_bytes = encoded_block_bytes(io::staged_bytes_bound(e.bytes, chunks, n, planes * (n + 15 * chunks)));
    }
    const uint64_t bytes = allocator ? allocator->bytes_for(layout) : layout.total_bytes();
    if (bytes > f.decoded_bytes) f.chunks = std::max<uint32_t>(1, e.chunk_count);
    f.decoded_bytes = std::max(f.decoded_bytes, bytes);
    f.record_bytes = std::max(f.record_bytes, (e.bytes + kAlignmentSlack + 4095) / 4096 * 4096);
  }
  return f;
}

namespace {

struct HostBudget {
  uint64_t bytes;
  const char* reason;
};

// A share of what is available (plus what the pipeline already holds, which
// MemAvailable no longer counts), then the user's cap.
HostBudget host_budget(const BudgetReading& reading, const BudgetOptions& options) {
  HostBudget b{kFallbackHostBudget, "host memory unknown"};  // nothing readable: stay modest
  if (const uint64_t available = reading.host.available(); available > 0) {
    b.bytes = static_cast<uint64_t>(options.host_fraction * double(available + reading.held_bytes));
    const bool cgroup_tighter = reading.host.cgroup_headroom && *reading.host.cgroup_headroom < reading.host.mem_available;
    b.reason = cgroup_tighter ? "cgroup limit" : "host memory";
  } else if (options.memory_cap > 0) {
    b.bytes = options.memory_cap;
  }
  if (options.memory_cap > 0 && options.memory_cap <= b.bytes) b = {options.memory_cap, "--memory"};
  return b;
}

}  // namespace

WindowPlan plan_window(const FrameFootprint& frame, const BudgetReading& reading, const BudgetOptions& options,
                       int decode_threads) {
  WindowPlan plan;
  const uint64_t decoded = std::max<uint64_t>(frame.decoded_bytes, 1);
  const uint64_t record = frame.record_bytes;
  const HostBudget host = host_budget(reading, options);
  plan.host_budget = host.bytes;

  // Record buffers: enough frames decoding at once to keep every worker busy
  // (a big frame's chunks alone may do it), two being read (the read crew's
  // rounds), one to spare; fewer if that is what it takes to fit two frames.
  auto frames_with = [&](uint32_t r) { return host.bytes >= r * record ? (host.bytes - r * record) / decoded : 0; };
  const auto workers = static_cast<uint32_t>(std::max(1, decode_threads));
  uint32_t records = std::min(workers + 2, (workers + frame.chunks - 1) / frame.chunks + 3);
  uint64_t host_frames = frames_with(records);
  while (host_frames < 2 && records > 1) host_frames = frames_with(--records);

  struct Limit {
    uint64_t frames;
    const char* reason;
  };
  std::vector<Limit> limits = {{host_frames, host.reason}, {options.ring_capacity, "ring capacity"}};
  if (reading.device_available) {
    plan.device_budget = static_cast<uint64_t>(options.device_fraction * double(*reading.device_available));
    limits.push_back({plan.device_budget / decoded, "device memory"});
  }
  if (options.max_frames > 0) limits.push_back({options.max_frames, "--window"});
  const Limit tightest = *std::min_element(limits.begin(), limits.end(),
                                           [](const Limit& a, const Limit& b) { return a.frames < b.frames; });
  plan.limited_by = tightest.reason;
  plan.over_budget = tightest.frames < 2;
  plan.frames = std::max<uint32_t>(2, clamp_frames(tightest.frames));
  plan.record_buffers = std::min(records, plan.frames);
  return plan;
}

}  // namespace sluice::runtime
