// The pipeline's internals, shared by its parts:
//   pipeline.cpp       construction, restart and take, stats
//   delivery.cpp       entries to the consumer in schedule order, slots back
//   reader_thread.cpp  the reader thread: schedule, reads, dispatch
//   slot_window.cpp    the reader's window: slots, record buffers, memory held
//   read_demand.h      what the views need read of a frame
//   read_target.cpp    where a frame's bytes go, and in what pieces
//   record_reads.cpp   the pieces, read on the crew (read_crew.cpp), checked and relayed
//   decoders.cpp       TBB decode of a frame's chunks and its completion
#pragma once


#include "read_crew.h"

#include <array>
#include <atomic>
#include <chrono>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "aligned_buffer.h"
#include "counters.h"
#include "decoders.h"
#include "delivery.h"
#include "read_demand.h"
#include "record_reads.h"
#include "mpsc_ring.h"
#include "slot.h"
#include "slot_window.h"
#include "spsc_ring.h"
#include "wake.h"
#include "sluice/runtime/pipeline.h"
#include "sluice/runtime/frame_allocator.h"

namespace sluice::runtime::detail {

class PipelineCore;

// A whole record the crew reads while the reader thread finishes the frames
// before it (reader_thread.cpp: start_entry).
struct PendingRead {
  uint32_t slot = 0;
  uint64_t k = 0;                    // its schedule entry
  std::span<const std::byte> record; // what the frame sees of its record once read
  PieceRound round;
};

// The records read in the background, oldest first: as many as the crew
// has rounds. In place, because the crew holds their rounds by address.
class PendingReads {
 public:
  // `capacity`: the crew's rounds() (already 1 .. ReadCrew::kMostRounds).
  explicit PendingReads(int capacity) : capacity_(uint32_t(capacity)) {}
  uint32_t size() const { return size_; }
  bool full() const { return size_ == capacity_; }
  PendingRead& oldest() { return reads_[first_]; }
  const PendingRead& at(uint32_t i) const { return reads_[(first_ + i) % capacity_]; }
  PendingRead& push() { return reads_[(first_ + size_++) % capacity_]; }  // not full()
  void pop() {  // size() > 0
    first_ = (first_ + 1) % capacity_;
    --size_;
  }

 private:
  std::array<PendingRead, ReadCrew::kMostRounds> reads_;
  uint32_t capacity_;
  uint32_t first_ = 0, size_ = 0;
};

// What only the reader thread touches.
struct ReaderState {
  ReaderState(const SlotWindow::Parts& parts, const WindowPlan& initial, int rounds) : window(parts, initial), pending(rounds) {}
  uint64_t generation = ~uint64_t(0);
  PlaybackSchedule schedule;
  uint64_t next_k = 0;                  // next entry of the schedule to fetch
  uint32_t out = 0;                     // entries pushed and not yet returned
  SlotWindow window;
  PendingReads pending;                 // records read in the background
  // Slots out of the window's lists: published and not returned, or read in the background.
  uint32_t in_flight() const { return out + pending.size(); }
};

class PipelineCore {
 public:
  PipelineCore(const io::ContainerReader& reader, FrameAllocator& allocator, PipelineOptions options);
  ~PipelineCore();

  // --- consumer side (pipeline.cpp; the rest is delivery_'s) ---
  uint64_t restart(const PlaybackSchedule& schedule);
  FrameHandle take();
  void release(uint32_t slot) { delivery_.release(slot); }  // a handle's release
  const Slot& slot(uint32_t s) const { return slots_[s]; }
  // The consumer's, while it holds the slot's handle (FrameHandle::spoil).
  void spoil(uint32_t s) { slots_[s].spoiled = true; }
  PipelineStats stats() const;

  const io::ContainerReader& reader_;
  FrameAllocator& allocator_;
  const PipelineOptions options_;

  // DecodeMode::World: chunks are converted to world-unit arrays.
  bool world() const { return options_.decode.mode == DecodeMode::World; }
 private:
  friend class sluice::runtime::Pipeline;
  enum class Start { Pushed, Cancelled, Blocked };

  // reader thread (reader_thread.cpp)
  void reader_main();
  bool reader_iteration(ReaderState& rs);  // false: nothing to do until woken
  void adopt_schedule(ReaderState& rs);
  void collect_returns(ReaderState& rs);
  // What the reader's window works on (slot_window.h).
  SlotWindow::Parts window_parts();
  Start start_entry(ReaderState& rs, uint64_t k, uint64_t frame);
  // Where a frame's bytes go: its record buffer, or (kept-encoded frames from
  // a buffered source) straight into its staged area, the record being its
  // prefix so that no worker copies it. Allocates.
  struct ReadTarget {
    std::span<std::byte> dst;     // the read lands here
    uint64_t offset = 0;          // the file offset of dst[0]
    uint64_t need = 0;            // bytes of dst that come from the file (the rest is alignment padding)
    std::span<std::byte> record;  // the frame's record (or its wanted prefix) once read, in dst's buffer
    bool by_chunks = false;       // chunks_to_read(): the slot's wanted chunks are read and checked, not dst
    bool by_runs = false;         // runs_to_read(): the runs of the slot's wanted chunks (slot.runs), not dst
  };
  ReadTarget record_target(ReaderState& rs, Slot& slot, uint32_t record);
  ReadTarget staged_target(ReaderState& rs, Slot& slot);
  bool reads_in_place() const;
  void hint_chunks(const Slot& slot);  // will_need for the slot's wanted chunks, close runs joined
  // Whether the layers left out of options_.layers let the frame be read as
  // a prefix of its record: they include the layer written last.
  bool reads_prefix(const io::FrameIndexEntry& e) const;
  // A prefix read: the record's table is read and parsed now, on this
  // thread; returns what is left to read (the payloads up to the last
  // wanted layer's), which may be nothing.
  ReadTarget read_table(Slot& slot, const ReadTarget& whole);
  // A checked read: keeps the wanted layers' chunks, checks that their
  // payloads lie in `record` past the `table`, and cuts them into pieces
  // (slot.piece_cuts). `record` starts at the frame's offset in the file.
  ReadTarget chunks_to_read(Slot& slot, std::span<std::byte> record, uint64_t record_bytes, uint64_t table);
  // A read by demand, not relayed: the wanted chunks (chunks_to_read) read
  // in runs of `whole`'s buffer past its first `skip` bytes (read_runs.h),
  // checked by the workers.
  ReadTarget runs_to_read(Slot& slot, const ReadTarget& whole, uint64_t record_bytes, uint64_t table, uint64_t skip);
  // relay.h: whether the next frame is relayed into device memory, its
  // target (the table into the record buffer, the area resident), and the
  // read of a piece's chunks through the relay (on a read thread).
  bool relays() const;
  ReadTarget relayed_target(ReaderState& rs, Slot& slot, uint32_t record);
  // A relayed frame with zstd planes (the mixed rule needs the record on
  // the host): read again into a staged area in host memory; later frames
  // are no longer relayed.
  void read_again_on_host(ReaderState& rs, Slot& slot);
  // The whole record in the background: with the crew's rounds all in
  // flight the oldest is joined first, this read begins, then that frame is
  // finished.
  void begin_background_read(ReaderState& rs, uint32_t s, uint64_t k, const ReadTarget& target);
  // Joins the oldest pending read and finishes its frame; false if none was
  // pending.
  bool settle_pending(ReaderState& rs);
  // The same for every pending read, oldest first: before anything that
  // publishes an entry or reads on this thread.
  void settle_all_pending(ReaderState& rs);
  enum class ReadOutcome { Read, Cancelled, Failed };
  ReadOutcome join_pending(ReaderState& rs, FrameError& error);
  void finish_read(ReaderState& rs, uint32_t s, uint64_t k, ReadOutcome outcome, FrameError error);
  // Parses the record and hands the frame to the decode workers (or fails it).
  void finish_entry(ReaderState& rs, uint32_t s, uint64_t k);
  void abandon_read(ReaderState& rs, uint32_t s);
  void set_layout(Slot& slot, uint64_t particles, uint64_t encoded_bytes) const;
  void move_to_larger_area(ReaderState& rs, Slot& slot, uint64_t staged_bytes);
  void prepare_decode(ReaderState& rs, Slot& slot);
  void publish(ReaderState& rs, uint32_t s, uint64_t k);
  void fail(ReaderState& rs, uint32_t s, uint64_t k, FrameError error);

  void wake_reader() { wake(reader_wake_); }

  // Fixed at construction.
  bool relay_off_ = false;       // the reader thread's: a relayed frame had zstd planes
  std::vector<uint32_t> stream_of_attribute_;  // header attribute -> decoded stream, or ~0u
  std::vector<size_t> attribute_of_stream_;    // decoded stream -> header attribute
  uint32_t attribute_streams_ = 0;
  FrameFootprint footprint_;
  io::ErrorLocation record_where_;  // the reader thread's: the file, and the frame it parses
  const uint32_t most_chunks_;      // of any frame in the file: a slot's chunk table is sized for it once
  WindowPlan initial_plan_;  // the reader starts from it
  int decode_threads_ = 1;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();

  // Slots, rings and record buffers (capacities fixed at construction).
  uint32_t slot_count_ = 0;
  std::unique_ptr<Slot[]> slots_;
  Delivery delivery_;                 // entries to the consumer, slots back (delivery.h)
  std::vector<AlignedBuffer> records_;

  // What the views need read (set_demand), applied by the reader thread
  // per frame (read_demand.h). A demand that leaves tiers out is read in
  // runs of its chunks (table first), the CPU decode path too, O_DIRECT too
  // (the runs are aligned).
  ReadDemand demand_;

  // Control: the schedule the consumer asked for, picked up by the reader.
  std::mutex control_mutex_;
  PlaybackSchedule requested_;             // guarded by control_mutex_
  std::atomic<uint64_t> generation_{0};    // written under control_mutex_
  std::atomic<bool> stopping_{false};
  std::atomic<uint32_t> reader_wake_{0};   // bumped whenever the reader may have work
  std::atomic<bool> reader_failed_{false};
  FrameError fatal_;                       // written before reader_failed_ is set

  // Stats.
  Counters counters_;

  // The decode workers (decoders.h): made once the attribute streams are known.
  std::optional<Decoders> decoders_;
  // Reads on the crew (record_reads.h): made once the source and the
  // thread count are known.
  std::optional<RecordReads> reads_;

  std::thread reader_thread_;  // last: started once everything above exists
};

}  // namespace sluice::runtime::detail
