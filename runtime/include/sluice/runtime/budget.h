// sluice/runtime/budget.h: how much memory the prefetch window may use.
//
// Host memory comes from the kernel (/proc/meminfo MemAvailable) and from the
// memory cgroup the process runs in (v2: memory.max - memory.current, v1:
// memory.limit_in_bytes - memory.usage_in_bytes, at every level up to the
// root), with the cgroup's reclaimable page cache (memory.stat: active and
// inactive file pages, less dirty and writeback) counted as available. Device memory comes from whoever owns the GPU, through
// DeviceMemoryBudget (the renderer reads VK_EXT_memory_budget).
//
// Units: bytes everywhere.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

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

// A device budget of a fixed size: for tests, headless runs and benchmarks.
class FixedDeviceBudget final : public DeviceMemoryBudget {
 public:
  explicit FixedDeviceBudget(uint64_t bytes) : bytes_(bytes) {}
  uint64_t available_bytes() const override { return bytes_; }

 private:
  uint64_t bytes_;
};

}  // namespace sluice::runtime
