// The pipeline's counters: written by the thread that does the work
// (relaxed atomics), read by PipelineCore::stats() from any thread.
#pragma once

#include <atomic>
#include <cstdint>

namespace sluice::runtime::detail {

// Per decode worker, on its own cache line: workers never share a written line.
struct alignas(64) WorkerCounters {
  std::atomic<uint64_t> chunks{0};
  std::atomic<uint64_t> output_bytes{0};
  std::atomic<uint64_t> busy_ns{0};
};

struct Counters {
  std::atomic<uint64_t> record_bytes{0}, frames_by_demand{0}, runs_read{0}, run_bytes_asked{0};
  std::atomic<uint64_t> bytes_read{0}, read_ns{0}, frames_read{0}, frames_in_place{0}, frames_relayed{0}, cache_hits{0};
  std::atomic<uint64_t> frames_decoded{0}, decoded_bytes{0}, frames_cancelled{0};
  std::atomic<uint64_t> frames_delivered{0}, frames_failed{0};
  std::atomic<uint64_t> held_bytes{0}, peak_record_bytes{0};
  std::atomic<uint32_t> window_frames{0}, active_frames{0}, record_buffers{0}, frames_ready{0};
  // The read threads' time on relayed frames, by part (PipelineStats::RelayTimes).
  std::atomic<uint64_t> relay_claim_ns{0}, relay_copy_ns{0}, relay_check_ns{0}, relay_plan_ns{0}, relay_send_ns{0};
};

}  // namespace sluice::runtime::detail
