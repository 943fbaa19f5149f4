// sluice/runtime/pipeline.h: frames from disk to a consumer, in order.
//
//   reader thread ──(pread, fadvise, O_DIRECT)──> record buffers
//        │ parse the frame table, FrameAllocator::allocate
//        v
//   TBB decode workers: chunks of a frame in parallel, several frames at once,
//        │ written straight into the allocator's buffers
//        v
//   delivery ring (SPSC, schedule order) ──> ONE consumer: peek / take / drop
//        ^                                        │
//        └──────────── return ring (SPSC) <───────┘ release
//
// The reader fetches the entries of a PlaybackSchedule in order, as far
// ahead as the prefetch window allows (budget.h); it blocks, never spins,
// when the window is full. Frames the consumer released stay decoded behind
// the playhead (a quarter of the window is kept for them) so reversing and
// scrubbing back find them at once. restart() starts a new schedule under a
// new generation number: queued and in-flight work of older generations is
// dropped (decode skips the chunks it has not started), never delivered and
// never waited for.
//
// Threads. One consumer thread calls everything marked "consumer". stats()
// and window() may be called from any thread. No mutex is taken per frame:
// slots move through an atomic state machine (slot.h) and the rings are
// lock-free; restart() takes a mutex shared only with the reader thread's
// pick-up of the new schedule (a rare control operation).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/budget.h"
#include "sluice/runtime/clock.h"
#include "sluice/runtime/demand.h"
#include "sluice/runtime/frame_allocator.h"
#include "sluice/runtime/record_source.h"
#include "sluice/runtime/stats.h"

namespace sluice::runtime {

// FrameError: a frame that could not be delivered.

// Why a frame failed: a read error or a file that ends early, a corrupt frame
// header, a corrupt chunk, or no memory for its buffers. `where` names the
// file and frame, and the chunk when one chunk was bad.
struct FrameError {
  io::ErrorLocation where;
  std::string message;  // what went wrong, without the location

  // "FILE: frame F, chunk C: message"
  std::string text() const;
  static FrameError from(const io::Error& e) { return {e.where(), e.message()}; }
};

struct WindowChange {
  uint32_t previous_frames = 0;  // 0 for the first plan
  WindowPlan plan;
};

// How records come off the disk.
struct ReadSettings {
  // Threads reading a record's pieces at once; 0: default_thread_split(cores,
  // DecodeMode::KeepEncoded), or a quarter of DecodeSettings::threads (1 to 4)
  // when that is given.
  int threads = 0;
  bool direct_io = false;  // O_DIRECT where the filesystem allows it (else buffered, said in stats)
  // Buffered reads copy out of the file's mapping with streaming stores
  // (FileRecordSource); false: pread. Stats say which is in use.
  bool mapped = true;
  uint64_t piece_bytes = 8 << 20;  // reads are split (a seek cancels a big read early; pieces go in parallel)
  // Records read at once, each a round of the read threads' pieces (1 to 4):
  // a thread done with one record's pieces goes on with the next record's
  // instead of waiting for the slowest piece. 2: measured on whole frames
  // (docs/runtime.md, "Two records in flight"); small frames read by the
  // view may want more.
  int rounds = 2;
  // Where records come from; null: the file, through FileRecordSource.
  std::shared_ptr<RecordSource> source;
};

enum class DecodeMode : uint8_t {
  Cpu,  // TBB workers decode every chunk into the frame's buffers
  // As Cpu, each chunk then converted to world units while still in the
  // worker's cache (io::convert_chunk): buffers().particles holds the frame
  // as io::world_spans() lays it out (float32 positions, one float32 array
  // per decoded attribute, LOD values, layers), and there are no attribute
  // streams. For consumers that want plain arrays (runtime::ParticleStream).
  World,
  // Frames stay encoded for a GPU decoder (io/gpu_decode_plan.h, the
  // renderer's commit): the workers check each chunk's checksum,
  // copy its payload into the frame's buffer and inflate its zstd planes
  // there (nothing for files written for the GPU); the buffer ends with the
  // chunk plans. Needs io::gpu_decodable(file) (the constructor throws
  // io::Error otherwise). When the allocator offers a relay (frame_allocator.h) and
  // reads are buffered, frames are relayed instead: their areas are
  // resident (device memory), filled as the read threads read, checked and
  // planned chunk by chunk, with no worker pass; FrameHandle::layout().resident
  // says so, and buffers().particles is then empty (the plan's tables travel
  // with gpu_plan()).
  KeepEncoded,
};

struct DecodeSettings {
  DecodeMode mode = DecodeMode::Cpu;
  int threads = 0;  // TBB workers; 0: default_thread_split()
  // Cpu: attribute streams to decode (indices into the file header's list);
  // nullopt: all of them.
  std::optional<std::vector<uint32_t>> attributes;
  // KeepEncoded: the attribute the plan decodes (file index; -1: none).
  int color_attribute = -1;
};

// How much memory the window of frames in flight may take (budget.h).
struct WindowSettings {
  BudgetOptions budget;
  const DeviceMemoryBudget* device_budget = nullptr;  // borrowed; null: no device limit
  uint32_t reevaluate_every = 32;                     // frames started between budget re-readings
  // Slow start: use a few slots first and grow toward the planned window only
  // while decoding keeps ahead of the consumer, so fresh buffers (a page
  // fault per 4 KiB on first use) are not paid for by every frame of a long
  // window. Turn off when the allocator hands out memory already touched (a
  // preallocated staging ring): the whole window is then used at once.
  bool slow_start = true;
  // Called when the window is planned (on the constructing thread) and when
  // it changes (on the reader thread). For logging: must not call the pipeline.
  std::function<void(const WindowChange&)> on_change;
};

// Fault injection, for tests; empty otherwise. Called on a decode worker
// before each chunk (it may block, holding that decode mid-way, or throw:
// the frame then fails) and on the reader thread just before a frame is
// handed to the decode workers (it may throw, as that hand-off's own
// allocation can: the frame then fails).
struct FaultHooks {
  std::function<void(uint64_t frame, size_t chunk)> before_decode_chunk;
  std::function<void(uint64_t frame)> before_decode_handoff;
};

struct PipelineOptions {
  // What to read. Layers (format 1.3): a frame's chunks of other layers are
  // never read: with the surface set, a layered frame's interior is skipped
  // on disk (its payloads come last in the record). Frames without layers
  // are read whole whatever the set.
  io::LayerSet layers = io::LayerSet::particles();
  // What the views draw (demand.h): of each frame it starts reading, the
  // reader reads only the LOD tiers of each cell this demand needs (cells
  // no view sees not at all). set_demand() replaces it while playing. The
  // default (no views) reads every tier. Reads by O_DIRECT read whole
  // records and decode only the demanded tiers.
  ViewDemand demand;
  ReadSettings read;
  DecodeSettings decode;
  WindowSettings window;
  FaultHooks faults;
};

// How the pipeline shares `cores` by default: one read thread per 4 cores
// (1 to 4) and, from 8 cores on, the others decode, so that readers and
// workers do not fight over cores; below 8 cores every core decodes
// (copying out of the page cache slows while the workers load memory).
//
// World frames (DecodeMode::World) take one read thread per 8 cores (1 to
// 4): their workers also convert every chunk to float arrays, and on 16
// cores 2 readers gave Python's streaming 1.08x the frames/s of 4.
//
// Frames kept encoded for the GPU (DecodeMode::KeepEncoded) are checked as they are
// read, which leaves the workers only zstd planes to inflate, so reading
// takes thirteen sixteenths of the cores, 1 to 13, and the rest are
// workers. docs/measurements.md ("Checked as read" and the thread split)
// has the measurements behind both splits.
struct ThreadSplit {
  int decode = 1;
  int read = 1;
};
ThreadSplit default_thread_split(int cores, DecodeMode mode = DecodeMode::Cpu);

enum class EntryStatus : uint8_t {
  None,     // not fetched yet (or the schedule has ended: see NextEntry::end)
  Pending,  // being decoded
  Ready,    // decoded: take() it
  Failed,   // could not be read or decoded: take() it to get the error
};

struct NextEntry {
  EntryStatus status = EntryStatus::None;
  bool end = false;        // the schedule has no such entry: nothing more will come
  uint64_t sequence = 0;   // index in the current schedule
  uint64_t frame = 0;      // frame number in the file (valid unless `end`)
};

class Pipeline;
namespace detail {
class PipelineCore;  // runtime/src/pipeline_core.h
}

// What a delivered frame's buffers hold (FrameHandle::content()).
enum class FrameContent : uint8_t {
  Decoded,  // buffers().particles: decoded particles (io::decoded_particle_bytes each); attributes: decoded streams
  World,    // buffers().particles: world-unit arrays (DecodeMode::World, io::world_spans); no attribute streams
  Encoded,  // buffers().particles: the staged area that gpu_plan() plans (io/gpu_decode_plan.h), to decode on the GPU
  Relayed,  // already in device memory (layout().resident); buffers().particles is empty, gpu_plan() has the tables
};

// A frame handed to the consumer. Move-only; destroying or reset()ing it
// gives the frame back. Consumer thread only; must not outlive its Pipeline.
// Buffers are read-only for the consumer and stay valid until the release.
class FrameHandle {
 public:
  FrameHandle() = default;
  FrameHandle(FrameHandle&& other) noexcept;
  FrameHandle& operator=(FrameHandle&& other) noexcept;
  ~FrameHandle() { reset(); }

  bool empty() const { return owner_ == nullptr && !error_; }
  bool failed() const { return error_ != nullptr; }
  const FrameError* error() const { return error_.get(); }  // when failed()

  uint64_t frame() const { return frame_; }
  uint64_t generation() const { return generation_; }
  uint64_t sequence() const { return sequence_; }

  // Valid when !empty() && !failed():
  const io::FrameHeader& header() const;           // chunk table: counts, AABBs (to dequantize), layers
  std::span<const uint64_t> chunk_first() const;   // first particle of each chunk
  const FrameLayout& layout() const;
  FrameContent content() const;                    // what buffers() holds
  const FrameBuffers& buffers() const;             // as content() says
  // Frames kept encoded (DecodeMode::KeepEncoded): the plan of the
  // staged area in buffers().particles; null otherwise.
  const io::GpuDecodePlan* gpu_plan() const;

  void reset();
  // Says the holder changed the frame's buffers: once released, the frame is
  // read again rather than served from them (a loop or seek back would
  // otherwise get the changed values).
  void spoil();

 private:
  friend class detail::PipelineCore;
  friend class Pipeline;
  detail::PipelineCore* owner_ = nullptr;
  uint32_t slot_ = 0;
  uint64_t frame_ = 0, generation_ = 0, sequence_ = 0;
  std::unique_ptr<FrameError> error_;
};

class Pipeline {
 public:
  // Borrowed: `reader` and `allocator` must outlive the pipeline. Plans the
  // window and starts the reader thread, idle until restart(). Throws
  // io::Error if an attribute index is out of range.
  Pipeline(const io::ContainerReader& reader, FrameAllocator& allocator, PipelineOptions options = {});
  // Stops the reader, waits for decode tasks (they skip what is left) and
  // gives every buffer back to the allocator. Handles must be gone by then.
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Consumer: plays `schedule` from its entry 0 under a new generation;
  // everything of older generations is dropped. Returns the generation.
  // frame_count may be less than the file's (a loop over its first frames);
  // throws runtime::Error if it is more, or stride is 0, or the
  // direction is not +1 or -1.
  uint64_t restart(const PlaybackSchedule& schedule);
  const PlaybackSchedule& schedule() const;  // consumer
  uint64_t generation() const;               // consumer

  // Consumer: the i-th entry not yet taken, without waiting.
  NextEntry peek(size_t i = 0);
  // Consumer: blocks until the next entry is Ready or Failed, or returns
  // with `end` set when the schedule has no next entry. Releasing frames is
  // the consumer's job: the reader keeps at most most_ahead() frames ahead,
  // handles held included, so with that many handles held and no entry
  // queued nothing could arrive, and wait_next() throws runtime::Error
  // instead of waiting forever.
  NextEntry wait_next();
  // Consumer: takes the next entry, which must be Ready or Failed (a failed
  // handle carries the error; its frame is already given back). Throws
  // runtime::Error otherwise.
  FrameHandle take();
  // Consumer: skips the next entry, whatever its state; work still pending
  // for it is abandoned.
  void drop();
  // Consumer: entries decoded and waiting.
  uint32_t ready_count();

  // Any thread.
  PipelineStats stats() const;
  uint32_t window() const;
  // Frames the reader keeps ahead of the playhead, handles the consumer
  // holds included: window() - window() / 4 (the rest is kept behind). A
  // consumer that waits holds fewer.
  uint32_t most_ahead() const;
  std::string io_mode() const;
  const io::ContainerReader& reader() const;
  // Set if the reader thread stopped on an error outside any frame (out of
  // memory for its own bookkeeping). Consumer.
  std::optional<FrameError> fatal_error() const;

  // Any thread: the demand of frames started from now on (latest wins; no
  // allocation, and the reader thread takes it without a lock). Frames
  // already read keep the tiers they were read with: short_of() tells, and
  // a player reads the frame on screen again when it is (refinement).
  void set_demand(const ViewDemand& demand);
  // Consumer: whether `demand` needs a tier of `frame` (a handle of this
  // pipeline, not empty or failed) that it was read without.
  bool short_of(const FrameHandle& frame, const ViewDemand& demand) const;

 private:
  std::unique_ptr<detail::PipelineCore> core_;
};

}  // namespace sluice::runtime
