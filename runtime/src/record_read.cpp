// Reading a frame record: in pieces (so a seek cancels a big read early),
// several at once when read_threads > 1 (read_crew.h). One thread copying
// out of the page cache tops out well below what the decode workers take.
#include <algorithm>
#include <chrono>

#include "pipeline_core.h"

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

void PipelineCore::read_piece(std::span<std::byte> piece, uint64_t offset, uint64_t required, uint64_t frame,
                              uint64_t frame_end) {
  uint64_t got = 0;
  while (got < required) {  // the source may return less than asked: carry on from there
    const size_t n = source_->read_at(piece.subspan(got), offset + got);
    if (n == 0) {
      throw io::Error(reader_.location(frame), "the file ends at byte " + std::to_string(offset + got) +
                                                   " but the frame runs to byte " + std::to_string(frame_end) +
                                                   " (short read: was the file cut while playing?)");
    }
    got += n;
    counters_.bytes_read.fetch_add(n, kRelaxed);
  }
}

void PipelineCore::begin_pieces(PieceRound& round, std::span<std::byte> dst, uint64_t offset, uint64_t need,
                                uint64_t frame, uint64_t generation) {
  const uint64_t align = std::max<size_t>(1, source_->alignment());
  // Pieces of at most read_piece_bytes, as many as a multiple of the
  // threads reading them, of equal size: every thread reads the same share
  // and none waits for a straggler at the end of the record (9 pieces of
  // 8 MiB on 4 threads take 3 rounds where 12 of 6 MiB take the same 3 with
  // less in each).
  const uint64_t most = round_up(std::max<uint64_t>(options_.read_piece_bytes, 1), align);
  const uint64_t threads = uint64_t(read_crew_.helpers()) + 1;
  const uint64_t at_most = (dst.size() + most - 1) / most;
  const uint64_t even = (at_most + threads - 1) / threads * threads;
  round.core = this;
  round.dst = dst;
  round.offset = offset;
  round.need = need;
  round.frame = frame;
  round.generation = generation;
  round.piece = std::max(align, round_up((dst.size() + even - 1) / std::max<uint64_t>(even, 1), align));
  round.count = (dst.size() + round.piece - 1) / round.piece;
  round.chunks = {};
  round.cuts = {};  // byte pieces (the round may have held a checked read before)
  begin_round(round);
}

void PipelineCore::begin_round(PieceRound& round) {
  round.gave_up.store(false, kRelaxed);
  if (read_crew_.in_flight() == 0) reading_since_ns_.store(steady_ns(), kRelaxed);
  read_crew_.begin(round.count, round);
}

void PipelineCore::begin_chunk_pieces(PieceRound& round, const Slot& slot, const ReadTarget& target, uint64_t generation) {
  round.core = this;
  round.dst = target.record;
  round.offset = target.offset;
  round.need = target.record.size();
  round.frame = slot.frame;
  round.generation = generation;
  round.chunks = slot.header.chunks;
  round.cuts = slot.piece_cuts;
  round.count = slot.piece_cuts.size() - 1;
  begin_round(round);
}

void PipelineCore::read_chunk(std::span<std::byte> dst, uint64_t offset, uint64_t frame, size_t c, uint64_t checksum) {
  uint64_t got_checksum = 0;
  const size_t got = source_->read_checked(dst, offset, got_checksum);
  counters_.bytes_read.fetch_add(got, kRelaxed);
  if (got == dst.size() && got_checksum == checksum) return;
  io::ErrorLocation at = reader_.location(frame);  // only now: it allocates
  at.chunk = c;
  if (got < dst.size()) {
    throw io::Error(at, "the file ends at byte " + std::to_string(offset + got) + " but the chunk runs to byte " +
                            std::to_string(offset + dst.size()) + " (short read: was the file cut while playing?)");
  }
  throw io::Error(at, "chunk checksum mismatch (the chunk's bytes are corrupt)");
}

// Piece p covers [p * piece, +piece) of dst; bytes past `need` are only
// alignment padding and may lie beyond the end of the file. With no helpers
// the crew runs the pieces in order on the joining thread.
void PieceRound::operator()(uint64_t p) const {
  if (gave_up.load(kRelaxed) || core->stopping_.load(kRelaxed) || core->generation_.load(kRelaxed) != generation) {
    gave_up.store(true, kRelaxed);
    return;
  }
  if (by_chunks()) {
    for (uint32_t c = cuts[p]; c < cuts[p + 1]; ++c) {
      const io::ChunkDesc& chunk = chunks[c];
      core->read_chunk(dst.subspan(chunk.offset, chunk.compressed_size), offset + chunk.offset, frame, c, chunk.checksum);
    }
    return;
  }
  const uint64_t at = p * piece;
  const uint64_t length = std::min(piece, dst.size() - at);
  core->read_piece(dst.subspan(at, length), offset + at, std::min(length, need - at), frame, offset + need);
}

// Read time is wall time with a round in flight: two rounds at once count
// once. A stretch still open counts up to now (stats()).
uint64_t PipelineCore::read_ns_now() const {
  const uint64_t since = reading_since_ns_.load(kRelaxed);
  const uint64_t closed = counters_.read_ns.load(kRelaxed);
  const uint64_t now = steady_ns();
  return closed + (since != 0 && now > since ? now - since : 0);
}

bool PipelineCore::join_pieces(PieceRound& round) {
  auto count_time = [&] {
    if (read_crew_.in_flight() > 0) return;
    // Cleared first: stats() may miss this stretch for an instant, never count it twice.
    const uint64_t since = reading_since_ns_.exchange(0, kRelaxed);
    counters_.read_ns.fetch_add(steady_ns() - since, kRelaxed);
  };
  try {
    read_crew_.join();
  } catch (...) {
    count_time();
    throw;
  }
  count_time();
  return !round.gave_up.load(kRelaxed);
}

}  // namespace sluice::runtime::detail
