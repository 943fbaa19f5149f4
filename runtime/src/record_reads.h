// Reading a frame's bytes: in pieces on the read crew (so a seek cancels a
// big read early, and several threads copy at once: one thread copying out
// of the page cache tops out well below what the decode workers take),
// whole byte ranges, runs of a demand's chunks, or chunks checked as read
// (and, for frames relayed to device memory, planned and sent through the
// relay as read).
//
// Threads: begin_*(), join() and drain() are the reader thread's, which
// has at most rounds() rounds in flight, each living until joined;
// read_piece() is also called there directly. The crew's threads run the
// rounds' pieces: they read through the source (RecordSource is called
// from several threads at once by contract), relay through PieceRelay (a
// piece is claimed and sent on the same thread) and write only their own
// pieces' bytes and the slot's plan entries for their own chunks. A round
// gives up at its next piece when a newer schedule (the generation) or
// stop comes. Counters are relaxed adds; read_ns_now() is any thread's.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>

#include "counters.h"
#include "read_crew.h"
#include "read_runs.h"
#include "slot.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/pipeline.h"
#include "sluice/runtime/record_source.h"
#include "sluice/runtime/frame_allocator.h"

namespace sluice::runtime::detail {

class RecordReads;
class RelayLaps;

// One read in pieces on the crew: the crew calls it once per piece until the
// round is joined, so it lives until then (on the caller's stack, or in
// ReaderState::pending).
struct PieceRound {
  RecordReads* reads = nullptr;
  std::span<std::byte> dst;  // [0, need) comes from the file at `offset`; the rest is alignment padding
  uint64_t offset = 0, need = 0, piece = 0, count = 0, frame = 0, generation = 0;
  // A checked read: piece p reads the record parts [cuts[p], cuts[p + 1])
  // (Slot::parts: records and fine parts) to their offsets in dst (the
  // record, at `offset` in the file) and checks them.
  std::span<const io::RecordPart> parts;
  std::span<const uint32_t> cuts;  // empty: byte pieces
  bool by_chunks() const { return !cuts.empty(); }
  // Reads by demand (read_runs.h): piece p reads runs[p] of dst, with no
  // check (the workers check the chunks; relayed frames are read by chunks).
  std::span<const ByteRun> runs;
  bool by_runs() const { return !runs.empty(); }
  Slot* relayed =
      nullptr;  // a relayed read (frame_allocator.h): the chunks go through the relay into this slot's area, not dst
  bool check = true;        // a checked read hashes each chunk as read; false: the decode workers check them
  mutable std::atomic<bool> gave_up{false};  // a newer schedule (or stop) came first: the pieces left are skipped
  void operator()(uint64_t p) const;
};

class RecordReads {
 public:
  // What the reads work on, owned by the pipeline and outliving them.
  struct Parts {
    const io::ContainerReader* reader = nullptr;
    const PipelineOptions* options = nullptr;
    Counters* counters = nullptr;
    const std::atomic<bool>* stopping = nullptr;
    const std::atomic<uint64_t>* generation = nullptr;
    std::shared_ptr<RecordSource> source;
    PieceRelay* relay = nullptr;  // the allocator's, for frames kept encoded; null: none
    int threads = 1;              // threads reading: the reader thread and threads - 1 helpers
    int rounds = 2;               // records read at once (ReadSettings::rounds)
  };
  explicit RecordReads(Parts parts);

  RecordSource& source() const { return *parts_.source; }
  PieceRelay* relay() const { return parts_.relay; }
  int threads() const { return parts_.threads; }
  int rounds() const { return crew_.rounds(); }

  // --- the reader thread ---
  // Reads [0, need) of `dst` from `offset` in pieces of equal size, as many
  // as a multiple of the threads; join() is false if a newer generation (or
  // stop) came first.
  void begin_bytes(PieceRound& round, std::span<std::byte> dst, uint64_t offset, uint64_t need, uint64_t frame,
                   uint64_t generation);
  // A checked read: piece p reads and checks the slot's chunks
  // [piece_cuts[p], piece_cuts[p + 1]) into `record` (at `offset` in the
  // file), or relays them when the slot is relayed.
  void begin_chunks(PieceRound& round, Slot& slot, std::span<std::byte> record, uint64_t offset, uint64_t generation);
  // The runs of a read by demand (slot.runs) into `dst`, unchecked.
  void begin_runs(PieceRound& round, Slot& slot, std::span<std::byte> dst, uint64_t offset, uint64_t need,
                  uint64_t generation);
  bool join(PieceRound& round);
  // Joins every round still in flight, their errors dropped (the reader
  // stopping: their frames go with the pipeline).
  void drain() noexcept;
  // [0, required) of `piece` from `offset`, carrying on after short reads;
  // io::Error naming the frame if the file ends first. `span`: through
  // RecordSource::read_span (a run of a demand: no mapping, whose faults
  // make the kernel read around them).
  void read_piece(std::span<std::byte> piece, uint64_t offset, uint64_t required, uint64_t frame, uint64_t frame_end,
                  bool span = false);

  // --- any thread ---
  uint64_t read_ns_now() const;  // time with a read in flight, the open stretch included
  uint64_t thread_busy_ns() const { return crew_.busy_ns(); }
  int helpers() const { return crew_.helpers(); }

 private:
  friend struct PieceRound;
  void begin(PieceRound& round);  // the common end: hands the round to the crew
  // Reads chunk `c` of the frame into `dst` from `offset` and checks it
  // against its checksum; throws io::Error naming the chunk.
  void read_chunk(std::span<std::byte> dst, uint64_t offset, uint64_t frame, size_t c, uint64_t checksum,
                  Stores stores = Stores::Streaming);
  // Checks chunk `c`'s bytes, already read, against its checksum; throws
  // io::Error naming the chunk.
  void check_chunk(std::span<const std::byte> bytes, uint64_t frame, size_t c, uint64_t checksum);
  void relay_chunks(const PieceRound& round, uint64_t p);
  void relay_large_part(Slot& slot, const io::RecordPart& part, uint64_t offset, RelayLaps& laps);

  Parts parts_;
  ReadCrew crew_;
  // When the crew last went from idle to reading (steady clock, ns; 0: idle).
  std::atomic<uint64_t> reading_since_ns_{0};
};

}  // namespace sluice::runtime::detail
