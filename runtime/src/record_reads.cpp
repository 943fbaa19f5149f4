#include "record_reads.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <vector>

#include "sluice/io/reader.h"
#include "sluice/io/gpu_decode_plan.h"

namespace sluice::runtime::detail {
namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

uint64_t round_up(uint64_t n, uint64_t to) { return (n + to - 1) / to * to; }

uint64_t steady_ns() {
  return static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                   std::chrono::steady_clock::now().time_since_epoch())
                                   .count());
}

}  // namespace

// The relay's parts timed on one read thread, each lap the time since the
// last; added to the shared counters once, when it ends, not per record
// (every read thread adds to those counters' cache line).
class RelayLaps {
 public:
  enum Part { Claim, Copy, Check, Plan, Send, kParts };
  explicit RelayLaps(Counters& counters) : counters_(counters), last_(steady_ns()) {}
  RelayLaps(const RelayLaps&) = delete;
  RelayLaps& operator=(const RelayLaps&) = delete;
  ~RelayLaps() {
    const std::array<std::atomic<uint64_t>*, kParts> into{&counters_.relay_claim_ns, &counters_.relay_copy_ns,
                                                          &counters_.relay_check_ns, &counters_.relay_plan_ns,
                                                          &counters_.relay_send_ns};
    for (int p = 0; p < kParts; ++p) {
      if (ns_[size_t(p)]) into[size_t(p)]->fetch_add(ns_[size_t(p)], kRelaxed);
    }
  }
  void lap(Part part) {
    const uint64_t now = steady_ns();
    ns_[size_t(part)] += now - last_;
    last_ = now;
  }

 private:
  Counters& counters_;
  uint64_t last_;
  std::array<uint64_t, kParts> ns_{};
};

RecordReads::RecordReads(Parts parts) : parts_(std::move(parts)) { crew_.start(parts_.threads - 1, parts_.rounds); }

void RecordReads::drain() noexcept {
  while (crew_.in_flight() > 0) {
    try {
      crew_.join();
    } catch (...) {  // the frame is dropped with the pipeline
    }
  }
}

void RecordReads::read_piece(std::span<std::byte> piece, uint64_t offset, uint64_t required, uint64_t frame,
                              uint64_t frame_end, bool span) {
  uint64_t got = 0;
  while (got < required) {  // the source may return less than asked: carry on from there
    const size_t n = span ? parts_.source->read_span(piece.subspan(got), offset + got) : parts_.source->read_at(piece.subspan(got), offset + got);
    if (n == 0) {
      throw io::Error(parts_.reader->location(frame), "the file ends at byte " + std::to_string(offset + got) +
                                                   " but the frame runs to byte " + std::to_string(frame_end) +
                                                   " (short read: was the file cut while playing?)");
    }
    got += n;
    parts_.counters->bytes_read.fetch_add(n, kRelaxed);
  }
}

void RecordReads::begin_bytes(PieceRound& round, std::span<std::byte> dst, uint64_t offset, uint64_t need,
                              uint64_t frame, uint64_t generation) {
  const uint64_t align = std::max<size_t>(1, parts_.source->alignment());
  // Pieces of at most ReadSettings::piece_bytes, as many as a multiple of the
  // threads reading them, of equal size: every thread reads the same share
  // and none waits for a straggler at the end of the record (9 pieces of
  // 8 MiB on 4 threads take 3 rounds where 12 of 6 MiB take the same 3 with
  // less in each).
  const uint64_t most = round_up(std::max<uint64_t>(parts_.options->read.piece_bytes, 1), align);
  const uint64_t threads = uint64_t(crew_.helpers()) + 1;
  const uint64_t at_most = (dst.size() + most - 1) / most;
  const uint64_t even = (at_most + threads - 1) / threads * threads;
  round.reads = this;
  round.dst = dst;
  round.offset = offset;
  round.need = need;
  round.frame = frame;
  round.generation = generation;
  round.piece = std::max(align, round_up((dst.size() + even - 1) / std::max<uint64_t>(even, 1), align));
  round.count = (dst.size() + round.piece - 1) / round.piece;
  round.parts = {};
  round.cuts = {};  // byte pieces (the round may have held a checked read before)
  round.runs = {};
  round.relayed = nullptr;
  begin(round);
}

void RecordReads::begin_runs(PieceRound& round, Slot& slot, std::span<std::byte> dst, uint64_t offset, uint64_t need,
                             uint64_t generation) {
  round.reads = this;
  round.dst = dst;
  round.offset = offset;
  round.need = need;
  round.frame = slot.frame;
  round.generation = generation;
  round.parts = {};
  round.cuts = {};
  round.runs = slot.runs;
  round.count = slot.runs.size();
  round.relayed = nullptr;
  round.check = false;
  begin(round);
}

void RecordReads::begin(PieceRound& round) {
  round.gave_up.store(false, kRelaxed);
  if (crew_.in_flight() == 0) reading_since_ns_.store(steady_ns(), kRelaxed);
  crew_.begin(round.count, round);
}

void RecordReads::begin_chunks(PieceRound& round, Slot& slot, std::span<std::byte> record, uint64_t offset,
                               uint64_t generation) {
  round.reads = this;
  round.dst = record;
  round.offset = offset;
  round.need = record.size();
  round.frame = slot.frame;
  round.generation = generation;
  round.parts = slot.parts;
  round.cuts = slot.piece_cuts;
  round.runs = {};
  round.count = slot.piece_cuts.size() - 1;
  round.relayed = slot.relayed ? &slot : nullptr;
  round.check = slot.checked_on_read;
  begin(round);
}

void RecordReads::read_chunk(std::span<std::byte> dst, uint64_t offset, uint64_t frame, size_t c, uint64_t checksum,
                              Stores stores) {
  uint64_t got_checksum = 0;
  const size_t got = parts_.source->read_checked(dst, offset, got_checksum, stores);
  parts_.counters->bytes_read.fetch_add(got, kRelaxed);
  if (got == dst.size() && got_checksum == checksum) return;
  io::ErrorLocation at = parts_.reader->location(frame);  // only now: it allocates
  at.chunk = c;
  if (got < dst.size()) {
    throw io::Error(at, "the file ends at byte " + std::to_string(offset + got) + " but the chunk runs to byte " +
                            std::to_string(offset + dst.size()) + " (short read: was the file cut while playing?)");
  }
  throw io::Error(at, "chunk checksum mismatch (the chunk's bytes are corrupt)");
}

void RecordReads::check_chunk(std::span<const std::byte> bytes, uint64_t frame, size_t c, uint64_t checksum) {
  if (io::chunk_checksum(bytes) == checksum) return;
  io::ErrorLocation at = parts_.reader->location(frame);  // only now: it allocates
  at.chunk = c;
  throw io::Error(at, "chunk checksum mismatch (the chunk's bytes are corrupt)");
}

// Piece p covers [p * piece, +piece) of dst; bytes past `need` are only
// alignment padding and may lie beyond the end of the file. With no helpers
// the crew runs the pieces in order on the joining thread.
void PieceRound::operator()(uint64_t p) const {
  if (gave_up.load(kRelaxed) || reads->parts_.stopping->load(kRelaxed) || reads->parts_.generation->load(kRelaxed) != generation) {
    gave_up.store(true, kRelaxed);
    return;
  }
  if (by_runs()) {
    const ByteRun& run = runs[p];
    reads->read_piece(dst.subspan(run.at, run.length), offset + run.at, run.required, frame, offset + run.at + run.required,
                     true);
    return;
  }
  if (by_chunks() && relayed) {
    reads->relay_chunks(*this, p);
    return;
  }
  if (by_chunks()) {
    for (uint32_t c = cuts[p]; c < cuts[p + 1]; ++c) {
      const io::RecordPart& part = parts[c];
      const std::span<std::byte> into = dst.subspan(part.offset, part.size);
      if (check) {
        reads->read_chunk(into, offset + part.offset, frame, part.chunk, part.checksum);
      } else {  // decode_chunk checks it: hashing it here too would read it twice
        const uint64_t at = offset + part.offset;
        reads->read_piece(into, at, into.size(), frame, at + into.size());
      }
    }
    return;
  }
  const uint64_t at = p * piece;
  const uint64_t length = std::min(piece, dst.size() - at);
  reads->read_piece(dst.subspan(at, length), offset + at, std::min(length, need - at), frame, offset + need);
}

namespace {

// One run of a demand in a ring slot: parts [first, last), whose bytes
// [from, from + bytes) of the record (gaps read through included) lie at
// `at` in the slot.
struct SlotRun {
  uint32_t first = 0, last = 0;
  uint64_t from = 0, bytes = 0, at = 0;
};

// The runs of a demand (as plan_runs() joins parts) from part `c` on that
// fit one after another into a ring slot of `most` bytes, at most `end`;
// none when part `c` alone is larger (the caller relays such a part
// apart). Returns the part after the last.
uint32_t gather_runs(std::span<const io::RecordPart> parts, uint32_t c, uint32_t end, uint64_t most,
                     std::vector<SlotRun>& runs) {
  runs.clear();
  uint64_t used = 0;
  while (c < end && parts[c].size <= most - used) {
    const uint64_t from = parts[c].offset;
    uint64_t bytes = 0;
    uint32_t last = c;
    while (last < end) {
      const io::RecordPart& next = parts[last];
      if (last > c && !joins_run(from, from + bytes, next.offset, kRunGap)) break;
      if (next.offset < from || next.offset + next.size - from > most - used) break;
      bytes = std::max(bytes, next.offset + next.size - from);
      ++last;
    }
    runs.push_back({c, last, from, bytes, used});
    used += bytes;
    c = last;
  }
  return c;
}

}  // namespace

// A relayed piece: its parts (records and fine parts), packed one after
// another into ring slots (as many as fit each), read out of the page
// cache with plain stores, checked and planned while the cache holds them,
// then sent to their place in the frame's resident area, a slot in one
// send (each send is a queue submission on the GPU's side). Parts that
// follow each other in the record go as one range. By demand, a slot holds
// as many of the demand's runs as fit, each read with one read of its own.
void RecordReads::relay_chunks(const PieceRound& round, uint64_t p) {
  Slot& slot = *round.relayed;
  const uint64_t most = parts_.relay->piece_bytes();
  const io::GpuPlanOptions plan_options{.color_attribute = parts_.options->decode.color_attribute};
  thread_local std::vector<PieceRelay::Range> ranges;  // grows once per thread
  thread_local std::vector<SlotRun> runs;              // by demand: the runs in the slot
  RelayLaps laps(*parts_.counters);
  uint32_t c = round.cuts[p];
  const uint32_t end = round.cuts[p + 1];
  while (c < end && !slot.relay_refused.load(kRelaxed)) {
    if (round.parts[c].size > most) {
      relay_large_part(slot, round.parts[c], round.offset, laps);
      ++c;
      continue;
    }
    const bool together = slot.by_demand;
    uint64_t bytes = 0;
    uint32_t last = c;
    if (together) {
      last = gather_runs(round.parts, c, end, most, runs);
      bytes = runs.back().at + runs.back().bytes;
    } else {
      while (last < end && bytes + round.parts[last].size <= most) bytes += round.parts[last++].size;
    }
    const std::span<std::byte> piece = parts_.relay->claim(bytes);
    laps.lap(RelayLaps::Claim);
    try {
      ranges.clear();
      if (together) {
        for (const SlotRun& run : runs) {
          const uint64_t from = round.offset + run.from;
          read_piece(piece.subspan(run.at, run.bytes), from, run.bytes, round.frame, from + run.bytes, true);
          parts_.counters->runs_read.fetch_add(1, kRelaxed);
          parts_.counters->run_bytes_asked.fetch_add(run.bytes, kRelaxed);
        }
        laps.lap(RelayLaps::Copy);
      }
      uint64_t at = 0;
      size_t r = 0;  // by demand: the run part k lies in
      for (uint32_t k = c; k < last; ++k) {
        const io::RecordPart& part = round.parts[k];
        if (together) {
          while (k >= runs[r].last) ++r;
          at = runs[r].at + (part.offset - runs[r].from);
        }
        const std::span<std::byte> dst = piece.subspan(at, part.size);
        if (together) {
          check_chunk(dst, round.frame, part.chunk, part.checksum);
          laps.lap(RelayLaps::Check);
        } else {  // copied and checked in one pass
          read_chunk(dst, round.offset + part.offset, round.frame, part.chunk, part.checksum, Stores::Cached);
          laps.lap(RelayLaps::Copy);
        }
        const bool planned =
            part.fine ? io::plan_gpu_fine(dst, slot.header, part.chunk, slot.plan, slot.where)
                      : io::plan_gpu_chunk(dst, slot.header, parts_.reader->header(), plan_options, part.chunk, slot.plan, slot.where);
        laps.lap(RelayLaps::Plan);
        if (!planned) {
          slot.relay_refused.store(true, kRelaxed);  // zstd planes: the frame is read again on the host
          parts_.relay->give_back(piece);
          return;
        }
        PieceRelay::Range* run = ranges.empty() ? nullptr : &ranges.back();
        if (run && run->from + run->bytes == at && run->to + run->bytes == part.offset) {
          run->bytes += part.size;
        } else {
          ranges.push_back({at, part.offset, part.size});
        }
        at += part.size;
      }
    } catch (...) {
      parts_.relay->give_back(piece);
      throw;
    }
    parts_.relay->send(piece, slot.buffers, ranges);
    laps.lap(RelayLaps::Send);
    c = last;
  }
}

// A part larger than a ring slot: read and checked whole into this
// thread's own buffer (kept for the next), then sent in slot-sized parts.
void RecordReads::relay_large_part(Slot& slot, const io::RecordPart& part, uint64_t offset, RelayLaps& laps) {
  thread_local std::vector<std::byte> whole;
  whole.resize(part.size);
  if (slot.by_demand) {  // no mapping (read_runs.h)
    read_piece(whole, offset + part.offset, whole.size(), slot.frame, offset + part.offset + whole.size(), true);
    laps.lap(RelayLaps::Copy);
    check_chunk(whole, slot.frame, part.chunk, part.checksum);
    laps.lap(RelayLaps::Check);
    parts_.counters->runs_read.fetch_add(1, kRelaxed);
    parts_.counters->run_bytes_asked.fetch_add(whole.size(), kRelaxed);
  } else {
    read_chunk(whole, offset + part.offset, slot.frame, part.chunk, part.checksum);
    laps.lap(RelayLaps::Copy);
  }
  const bool planned = part.fine ? io::plan_gpu_fine(whole, slot.header, part.chunk, slot.plan, slot.where)
                                  : io::plan_gpu_chunk(whole, slot.header, parts_.reader->header(),
                                                       {.color_attribute = parts_.options->decode.color_attribute},
                                                       part.chunk, slot.plan, slot.where);
  laps.lap(RelayLaps::Plan);
  if (!planned) {
    slot.relay_refused.store(true, kRelaxed);
    return;
  }
  const uint64_t most = parts_.relay->piece_bytes();
  for (uint64_t at = 0; at < whole.size(); at += most) {
    const uint64_t n = std::min<uint64_t>(most, whole.size() - at);
    const std::span<std::byte> piece = parts_.relay->claim(n);
    laps.lap(RelayLaps::Claim);
    std::memcpy(piece.data(), whole.data() + at, n);
    laps.lap(RelayLaps::Copy);
    const PieceRelay::Range range{0, part.offset + at, n};
    parts_.relay->send(piece, slot.buffers, {&range, 1});
    laps.lap(RelayLaps::Send);
  }
}

// Read time is wall time with a round in flight: two rounds at once count
// once. A stretch still open counts up to now (stats()).
uint64_t RecordReads::read_ns_now() const {
  const uint64_t since = reading_since_ns_.load(kRelaxed);
  const uint64_t closed = parts_.counters->read_ns.load(kRelaxed);
  const uint64_t now = steady_ns();
  return closed + (since != 0 && now > since ? now - since : 0);
}

bool RecordReads::join(PieceRound& round) {
  auto count_time = [&] {
    if (crew_.in_flight() > 0) return;
    // Cleared first: stats() may miss this stretch for an instant, never count it twice.
    const uint64_t since = reading_since_ns_.exchange(0, kRelaxed);
    parts_.counters->read_ns.fetch_add(steady_ns() - since, kRelaxed);
  };
  try {
    crew_.join();
  } catch (...) {
    count_time();
    throw;
  }
  count_time();
  return !round.gave_up.load(kRelaxed);
}

}  // namespace sluice::runtime::detail
