// sluice/runtime/stats.h: what the pipeline has done, as plain numbers.
//
// A PipelineStats is a snapshot of cumulative counters; rates come from two
// snapshots (rates_between). Snapshots may be taken from any thread; the
// counters are updated with relaxed atomics, so a snapshot is consistent per
// counter, not across counters. Units: bytes, seconds, frames.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sluice::runtime {

// One decode worker: a slot of the pipeline's TBB arena (a thread while it
// works there). Only slots that have decoded something are listed.
struct WorkerStats {
  uint32_t slot = 0;
  uint64_t chunks = 0;
  uint64_t output_bytes = 0;  // decoded bytes written
  double busy_seconds = 0;    // time spent decoding
};

struct PipelineStats {
  double elapsed_seconds = 0;  // since the pipeline was created
  std::string io_mode;         // how records are read ("pread, O_DIRECT", ...)

  // Reader thread.
  uint64_t bytes_read = 0;
  double read_seconds = 0;     // time with a read in progress (wall time, however many threads read)
  double read_thread_seconds = 0;  // time the read threads spent copying, summed over them
  uint32_t read_threads = 0;       // threads that read (the reader thread and its helpers)
  uint64_t frames_read = 0;
  // The whole records of the frames read (the index's sizes): bytes_read /
  // record_bytes is the share of the file a view's demand (demand.h) reads.
  uint64_t record_bytes = 0;
  uint64_t frames_by_demand = 0;  // frames read with some tier or cell left out
  // Reads by demand: the runs their wanted records were read in (records
  // close together share one, read_runs.h) and the bytes those runs cover
  // (the wanted records and the gaps read through).
  uint64_t runs_read = 0;
  uint64_t run_bytes = 0;
  // Kept-encoded frames read straight into their staged area and staged
  // there (no copy on the CPU; DecodeMode::KeepEncoded).
  uint64_t frames_in_place = 0;
  // ... of which relayed to device memory as read (runtime/frame_allocator.h).
  uint64_t frames_relayed = 0;
  // Where the read threads' time on relayed frames went, summed over the
  // threads: waiting for a ring slot (claim), copying into it, checking the
  // records' checksums, planning them for the GPU (their plane tables), and
  // handing the slot on (send).
  struct RelayTimes {
    double claim_seconds = 0, copy_seconds = 0, check_seconds = 0, plan_seconds = 0, send_seconds = 0;
  } relay;
  uint64_t cache_hits = 0;     // entries served from a frame kept in memory, no read or decode

  // Decode workers.
  uint64_t frames_decoded = 0;
  uint64_t decoded_bytes = 0;
  uint64_t frames_cancelled = 0;  // stale (after a seek) or dropped work abandoned before it finished
  std::vector<WorkerStats> workers;

  // Delivery to the consumer.
  uint64_t frames_delivered = 0;
  uint64_t frames_failed = 0;  // frames that could not be read or decoded
  uint64_t generation = 0;     // restarts (seeks, reversals) so far

  // Window.
  uint32_t window_frames = 0;   // the planned prefetch window (the most it may use)
  uint32_t active_frames = 0;   // how much of it is in use: it grows while decoding keeps ahead
  uint32_t record_buffers = 0;  // compressed records in flight at most
  uint32_t frames_ready = 0;    // decoded and waiting, as of the consumer's last look
  uint64_t held_bytes = 0;      // decoded buffers + record buffers the pipeline holds now
  uint64_t peak_record_bytes = 0;
};

struct PipelineRates {
  double seconds = 0;
  double frames_per_second = 0;            // delivered
  double read_mbps = 0;                    // MB read per second of the interval
  double read_busy_mbps = 0;               // MB per second spent reading: what storage gave
  double decode_mbps = 0;                  // MB of decoded output per second, all workers
  std::vector<double> worker_decode_mbps;  // per worker of `after`, per second it was busy
  std::vector<double> worker_busy;         // share of the interval each worker was busy, 0..1
};

// Rates over the interval between two snapshots of one pipeline (MB = 1e6 bytes).
PipelineRates rates_between(const PipelineStats& before, const PipelineStats& after);

}  // namespace sluice::runtime
