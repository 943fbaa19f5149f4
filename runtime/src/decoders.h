// The decode workers: each frame handed over is one TBB task in the
// pipeline's own arena, whose chunks are checked and decoded (or staged for
// the GPU, or converted to world units) in parallel, straight into the
// frame's buffers. The worker that finishes the last chunk settles the
// frame: Ready, Failed or Cancelled.
//
// Threads: prepare() and start() are the reader thread's; the workers run
// the tasks; stats() may be called from any thread. A frame's slot belongs
// to the workers from start() until its state leaves Decoding (a release
// store, then notify_all for a consumer waiting on it); its record buffer
// comes back to the reader through record_returns() (an MPSC ring that
// holds every record buffer, so a push cannot fail), and the reader is
// woken through the counter given in Parts. A frame of an older generation,
// or abandoned by the consumer, or the pipeline stopping, skips its
// remaining chunks and ends Cancelled.
#pragma once

#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "counters.h"
#include "mpsc_ring.h"
#include "slot.h"
#include "wake.h"
#include "sluice/io/codec.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::runtime::detail {

class Decoders {
 public:
  // What the workers work on, owned by the pipeline and outliving them.
  struct Parts {
    Slot* slots = nullptr;
    const io::ContainerReader* reader = nullptr;
    const PipelineOptions* options = nullptr;
    Counters* counters = nullptr;
    const std::atomic<bool>* stopping = nullptr;
    const std::atomic<uint64_t>* generation = nullptr;  // the schedule's (a newer one makes a frame stale)
    std::atomic<uint32_t>* reader_wake = nullptr;      // bumped when a frame is settled
    int threads = 1;                                   // workers (the arena's concurrency)
    size_t records = 1;                                // record buffers the ring must hold
    // Decoded attribute streams: header attribute -> stream (~0u: not
    // decoded), stream -> header attribute.
    std::vector<uint32_t> stream_of_attribute;
    std::vector<size_t> attribute_of_stream;
  };
  explicit Decoders(Parts parts);
  Decoders(const Decoders&) = delete;
  Decoders& operator=(const Decoders&) = delete;
  // Waits for the tasks still running (stopping, they skip their chunks).
  ~Decoders() { wait(); }

  // --- the reader thread ---
  // Before the frame is published as Decoding: its chunks counted.
  void prepare(Slot& slot);
  // Hands the prepared frame in slot `s` to the workers. Without memory for
  // the task, the frame fails in its place, as a decode would have failed it.
  void start(Slot& slot, uint32_t s) noexcept;
  // Frames handed over and not yet settled.
  const std::atomic<uint32_t>& in_flight() const { return frames_decoding_; }
  MpscRing<uint32_t>& record_returns() { return record_returns_; }

  // --- any thread ---
  void add_stats(PipelineStats& stats) const;  // the workers' counters
  void wait() noexcept;

 private:
  bool world() const { return parts_.options->decode.mode == DecodeMode::World; }
  // TBB numbers an arena's slots 0..max_concurrency (slot 0 is for a thread
  // joining from outside): one counter per slot.
  uint32_t worker_slots() const { return static_cast<uint32_t>(parts_.threads) + 1; }
  bool stale(const Slot& slot) const;
  void decode_frame(Slot& slot, uint32_t s) noexcept;
  void decode_chunk(Slot& slot, size_t c) noexcept;
  // A world-unit chunk: decoded into the worker's cache, then converted into the frame's arrays.
  void convert_chunk(Slot& slot, size_t c, io::DecodeScratch& scratch);
  void finish(uint32_t s);

  Parts parts_;
  MpscRing<uint32_t> record_returns_;  // workers -> reader
  std::atomic<uint32_t> frames_decoding_{0};
  std::unique_ptr<io::DecodeScratch[]> scratch_;  // one per arena slot (a worker's index)
  std::unique_ptr<WorkerCounters[]> workers_;
  // Our own arena, sized to the workers. The global_control lets TBB start
  // that many workers even where it would otherwise keep one core for a
  // master thread that never joins this arena.
  std::optional<tbb::global_control> parallelism_;
  tbb::task_arena arena_;
  tbb::task_group group_;
};

}  // namespace sluice::runtime::detail
