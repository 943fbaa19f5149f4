// sluice/runtime/budget.h: how much memory the prefetch window may use, and
// the window it allows.
//
// Host memory comes from the kernel (/proc/meminfo MemAvailable) and from the
// memory cgroup the process runs in (v2: memory.max - memory.current, v1:
// memory.limit_in_bytes - memory.usage_in_bytes, at every level up to the
// root), with the cgroup's reclaimable page cache (memory.stat: active and
// inactive file pages, less dirty and writeback) counted as available. Device memory comes from whoever owns the GPU,
// through DeviceMemoryBudget (the renderer reads VK_EXT_memory_budget).
//
// Units: bytes everywhere.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "sluice/io/format.h"
#include "sluice/runtime/frame_allocator.h"

namespace sluice::io {
class ContainerReader;
}  // namespace sluice::io

namespace sluice::runtime {

// Where the host figures are read from. Injectable so tests can point at
// fake files; the defaults are the real kernel interfaces.
struct HostMemoryPaths {
  std::string meminfo = "/proc/meminfo";
  std::string self_cgroup = "/proc/self/cgroup";  // which cgroup this process is in
  std::string cgroup_root = "/sys/fs/cgroup";     // where cgroupfs is mounted
};

// One reading of the host's memory.
struct HostMemory {
  uint64_t mem_available = 0;               // MemAvailable; 0 if it could not be read
  std::optional<uint64_t> cgroup_headroom;  // limit - (usage - file cache) of the tightest cgroup level; none if unlimited
  uint64_t cgroup_file_cache = 0;           // the reclaimable page cache counted at that level
  std::string cgroup_source;                // the limit file that set the headroom, for messages

  // What the process may still allocate: the smaller of the two. 0 when
  // nothing could be read (callers then fall back to their user cap).
  uint64_t available() const;
};

// Reads MemAvailable and the cgroup headroom. Never throws: files that are
// missing or unreadable count as "no information" (a cgroup level without a
// limit is skipped).
HostMemory read_host_memory(const HostMemoryPaths& paths = {});

// Parses a size as users type it: "8G", "512M", "1.5GiB", "64k", "1000000"
// (binary multiples: K = 1024). Returns nullopt on anything else.
std::optional<uint64_t> parse_byte_size(const std::string& text);

// Device memory the frame slots may use. Implemented by the renderer from
// VK_EXT_memory_budget (heap budget - heap usage + what its frame slots
// already hold). Called on the pipeline's reader thread, so implementations
// must be safe to call from a thread other than the one that renders.
class DeviceMemoryBudget {
 public:
  virtual ~DeviceMemoryBudget() = default;
  virtual uint64_t available_bytes() const = 0;
};

// The window: how many frames the pipeline may hold.
//
// The prefetch window is the number of decoded frames in memory at once:
// frames ahead of the playhead, the one on screen, and a few kept behind it so
// that reversing or scrubbing back shows them at once. It is
//
//   min(host budget / host bytes per frame,
//       device budget / device bytes per frame,
//       the user's frame cap, the ring capacity)      and never below 2.
//
// Host bytes per frame are the decoded buffers plus the compressed record the
// reader reads into; the reader keeps only a few record buffers (enough
// frames in flight to keep every decode worker busy, plus the one being
// read), so the plan says how many it may have.

// The largest frame of a file, in the pipeline's terms.
struct FrameFootprint {
  uint64_t decoded_bytes = 0;  // particle buffer + attribute streams, what FrameAllocator hands out
  uint64_t record_bytes = 0;   // compressed record, plus room to align it for O_DIRECT
  uint32_t chunks = 1;         // chunks of the largest frame: how many workers one frame keeps busy
};

// `attribute_streams`: how many attribute streams are decoded per frame;
// `allocator`, if given, says what its buffers really take (bytes_for);
// `layers`: the layers read (a record's size counts whole: the index does not
// say where its layers' payloads end); `encoded`: frames stay encoded for a
// GPU decoder (their record, plus a bound on what the CPU adds: every
// plane inflated, the chunk plans and the tile table); `particle_stride`:
// bytes per decoded particle (0: io::decoded_particle_bytes of the file's
// coding; frames converted to world units give io::world_particle_bytes and
// no attribute streams).
FrameFootprint largest_frame(const io::ContainerReader& reader, size_t attribute_streams,
                             const FrameAllocator* allocator = nullptr, io::LayerSet layers = io::LayerSet::particles(),
                             bool encoded = false, uint32_t particle_stride = 0);

struct BudgetOptions {
  uint64_t memory_cap = 0;       // user cap on host bytes (`--memory 8G`); 0: none
  uint32_t max_frames = 0;       // user cap on the window in frames (`--window`); 0: none
  double host_fraction = 0.5;    // share of the host's available memory the window may take
  double device_fraction = 0.8;  // share of the device budget
  uint32_t ring_capacity = 256;  // hard ceiling: the pipeline's slot and ring capacity
  HostMemoryPaths host_paths;    // where host memory is read from (tests inject fakes)
};

// Everything the window is computed from, read at one moment.
struct BudgetReading {
  HostMemory host;
  uint64_t held_bytes = 0;                   // what the pipeline holds now (counted as available to it)
  std::optional<uint64_t> device_available;  // none: no device limit
};

struct WindowPlan {
  uint32_t frames = 2;          // decoded frames in memory at once (>= 2)
  uint32_t record_buffers = 1;  // compressed records being read or decoded at once (>= 1)
  uint64_t host_budget = 0;     // bytes the plan may use on the host
  uint64_t device_budget = 0;   // bytes it may use on the device; 0 if there is no device limit
  std::string limited_by;    // "host memory", "cgroup limit", "--memory", "device memory", "--window", "ring capacity"
  bool over_budget = false;  // even 2 frames do not fit: the window is 2 anyway
};

// Pure function of its inputs; `decode_threads` sizes the record buffers.
WindowPlan plan_window(const FrameFootprint& frame, const BudgetReading& reading, const BudgetOptions& options,
                       int decode_threads);

}  // namespace sluice::runtime
