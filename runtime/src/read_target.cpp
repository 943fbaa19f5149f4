// Where a frame's bytes go and in what pieces: a record buffer, or the
// frame's staged area (frames kept encoded); the whole record, or its table
// first and then a prefix, or its wanted chunks checked as they are read.
// The reader thread's (reader_thread.cpp); the pieces are read by the crew
// (record_read.cpp).
#include <algorithm>
#include <string>

#include "pipeline_core.h"

namespace sluice::runtime::detail {
namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

uint64_t round_up(uint64_t n, uint64_t to) { return (n + to - 1) / to * to; }

}  // namespace

PipelineCore::ReadTarget PipelineCore::record_target(ReaderState& rs, Slot& slot, uint32_t record) {
  const io::FrameIndexEntry& e = reader_.index().frames[slot.frame];
  const uint64_t align = std::max<size_t>(1, reads_->source().alignment());
  const uint64_t begin = e.offset / align * align;
  const uint64_t need = e.offset + e.bytes - begin;  // bytes from `begin` the frame needs
  const uint64_t span = round_up(need, align);
  AlignedBuffer& buffer = rs.window.record_buffer(record, std::max<uint64_t>(footprint_.record_bytes, span));
  return {buffer.span().first(span), begin, need, buffer.span().subspan(e.offset - begin, e.bytes)};
}

bool PipelineCore::reads_in_place() const {
  return (options_.decode.mode == DecodeMode::KeepEncoded) && reads_->source().alignment() <= 1;
}

// The kernel is asked for every wanted part at once, runs less than
// kHintGap apart joined, so that storage has them all queued (the read
// threads then copy pages already on their way) and reads nothing else.
void PipelineCore::hint_chunks(const Slot& slot) {
  constexpr uint64_t kHintGap = 128 << 10;
  const uint64_t base = reader_.index().frames[slot.frame].offset;
  uint64_t from = 0, to = 0;
  for (const io::RecordPart& c : slot.parts) {
    if (to > from && c.offset <= to + kHintGap && c.offset >= from) {
      to = std::max(to, c.offset + c.size);
      continue;
    }
    if (to > from) reads_->source().will_need(base + from, to - from);
    from = c.offset;
    to = c.offset + c.size;
  }
  if (to > from) reads_->source().will_need(base + from, to - from);
}

bool PipelineCore::relays() const { return reads_->relay() != nullptr && !relay_off_ && reads_in_place(); }

// The area is resident (device memory, relay.h); only the table is read
// into host memory, the slot's record buffer. The area's size is the
// staged_target()'s; a frame with zstd planes is read again on the host.
PipelineCore::ReadTarget PipelineCore::relayed_target(ReaderState& rs, Slot& slot, uint32_t record) {
  const io::FrameIndexEntry& e = reader_.index().frames[slot.frame];
  set_layout(slot, e.count_in(options_.layers),
             encoded_block_bytes(io::staged_bytes_bound(e.bytes, e.chunk_count, e.particle_count, 0)));
  slot.layout.resident = true;
  rs.window.allocate_buffers(slot);
  const uint64_t table = std::min<uint64_t>(e.bytes, io::frame_table_bytes(e.chunk_count, reader_.header().attributes.size()));
  const std::span<std::byte> into = rs.window.record_buffer(record, table).span().first(table);
  return {into, e.offset, table, into};
}

// The area is sized for the record and its tables with no plane inflated
// (GPU-decodable files); prepare_decode moves a frame with zstd planes to a
// larger one. The record holds the slot's record buffer as a token only
// (it bounds the frames being read and staged at once), not its memory.
PipelineCore::ReadTarget PipelineCore::staged_target(ReaderState& rs, Slot& slot) {
  const io::FrameIndexEntry& e = reader_.index().frames[slot.frame];
  set_layout(slot, e.count_in(options_.layers),
             encoded_block_bytes(io::staged_bytes_bound(e.bytes, e.chunk_count, e.particle_count, 0)));
  rs.window.allocate_buffers(slot);
  if (slot.buffers.particles.size() < e.bytes) {
    throw io::Error(reader_.location(slot.frame), "the frame allocator returned buffers smaller than the frame");
  }
  const std::span<std::byte> area = slot.buffers.particles.first(e.bytes);
  return {area, e.offset, e.bytes, area};
}

// Payloads are written surface, blobs, interior (io/src/codec.cpp): leaving
// out the interior leaves a prefix to read. Leaving out only the blobs, in
// the middle, saves nothing: the whole record is read (in the background,
// two records at once) and their chunks are dropped.
bool PipelineCore::reads_prefix(const io::FrameIndexEntry& e) const {
  if (!e.layered()) return false;
  io::Layer last = io::Layer::Surface;
  if (e.layer_particles[size_t(io::Layer::Blobs)] > 0) last = io::Layer::Blobs;
  if (e.layer_particles[size_t(io::Layer::Interior)] > 0) last = io::Layer::Interior;
  return !options_.layers.has(last);
}

// The table is a few KiB: read here rather than as a crew round, so that the
// rounds in flight go on. Offsets stay aligned for O_DIRECT (record buffers
// only).
PipelineCore::ReadTarget PipelineCore::read_table(Slot& slot, const ReadTarget& whole) {
  const io::FrameIndexEntry& e = reader_.index().frames[slot.frame];
  const uint64_t align = std::max<size_t>(1, reads_->source().alignment());
  const uint64_t table = std::min<uint64_t>(e.bytes, io::frame_table_bytes(e.chunk_count, reader_.header().attributes.size()));
  const auto into = static_cast<uint64_t>(whole.record.data() - whole.dst.data());  // where the record starts in dst
  const uint64_t first = round_up(into + table, align);
  // By demand not through the mapping: a fault there makes the kernel read
  // around it (read_ahead_kb, doubled for sequential play) what the view leaves out.
  reads_->read_piece(whole.dst.first(first), whole.offset, into + table, slot.frame, whole.offset + whole.need, slot.by_demand);
  record_where_.frame = slot.frame;
  reader_.parse_table(slot.frame, whole.record.first(table), slot.header, record_where_);
  const uint64_t end = io::layers_end(slot.header, options_.layers, reader_.header().attributes.size());
  const uint64_t wanted = into + end;
  if (slot.relayed) return chunks_to_read(slot, {}, end, table);
  if (slot.by_demand) return runs_to_read(slot, whole, end, table, first);
  if (slot.checked_on_read || slot.by_demand) return chunks_to_read(slot, whole.record.first(end), end, table);
  reads_->source().will_need(whole.offset + first, wanted - std::min(wanted, first));
  ReadTarget rest;
  rest.offset = whole.offset + first;
  rest.record = whole.record.first(end);
  rest.dst = whole.dst.subspan(first, wanted > first ? round_up(wanted, align) - first : 0);
  rest.need = wanted > first ? wanted - first : 0;
  return rest;
}

// The wanted chunks, in pieces of about equal bytes: each piece copies its
// chunks and checks them as it goes (record_read.cpp). `record` is empty
// for a relayed frame: its chunks go through the relay, planned as they
// arrive.
PipelineCore::ReadTarget PipelineCore::chunks_to_read(Slot& slot, std::span<std::byte> record, uint64_t record_bytes,
                                                      uint64_t table) {
  io::keep_layers(slot.header, options_.layers);
  demand_.apply(slot);
  io::record_parts(slot.header, slot.parts);
  const std::vector<io::RecordPart>& parts = slot.parts;
  uint64_t total = 0;
  for (const io::RecordPart& part : parts) {
    // The payload is written where the table says: inside the record, past the table.
    if (part.offset < table || part.offset > record_bytes || part.size > record_bytes - part.offset) {
      io::ErrorLocation at = reader_.location(slot.frame);
      at.chunk = part.chunk;
      throw io::Error(at, std::string(part.fine ? "the chunk's fine part" : "the chunk's payload") + " (bytes " +
                              std::to_string(part.offset) + " to " + std::to_string(part.offset + part.size) +
                              ") lies outside the frame record's payloads (bytes " + std::to_string(table) + " to " +
                              std::to_string(record_bytes) + ")");
    }
    total += part.size;
  }
  hint_chunks(slot);
  if (slot.relayed) {
    io::plan_gpu_frame(slot.header, reader_.header(), {.color_attribute = options_.decode.color_attribute}, slot.plan,
                       reader_.location(slot.frame));
  }
  // As many pieces as byte pieces would be (a multiple of the threads
  // reading), at most one per chunk; cut where the running sum crosses each
  // equal share. A relayed piece fits a ring slot.
  uint64_t most = std::max<uint64_t>(options_.read.piece_bytes, 1);
  if (slot.relayed) most = std::min(most, std::max<uint64_t>(reads_->relay()->piece_bytes(), 1));
  const uint64_t threads = uint64_t(reads_->helpers()) + 1;
  const uint64_t at_most = (total + most - 1) / most;
  const uint64_t pieces = std::min<uint64_t>(parts.size(), (at_most + threads - 1) / threads * threads);
  slot.piece_cuts.clear();
  slot.piece_cuts.push_back(0);
  uint64_t sum = 0;
  for (size_t c = 0; c < parts.size(); ++c) {
    sum += parts[c].size;
    if (c + 1 == parts.size() || sum * pieces >= slot.piece_cuts.size() * total) slot.piece_cuts.push_back(static_cast<uint32_t>(c + 1));
  }
  ReadTarget target;
  target.record = record;
  target.offset = reader_.index().frames[slot.frame].offset;
  target.by_chunks = true;
  return target;
}

PipelineCore::ReadTarget PipelineCore::runs_to_read(Slot& slot, const ReadTarget& whole, uint64_t record_bytes,
                                                    uint64_t table, uint64_t skip) {
  chunks_to_read(slot, whole.record.first(record_bytes), record_bytes, table);
  const auto into = static_cast<uint64_t>(whole.record.data() - whole.dst.data());  // where the record starts in dst
  const RunLimits limits{.align = std::max<uint64_t>(1, reads_->source().alignment()),
                         .gap = kRunGap,
                         .piece = std::max<uint64_t>(options_.read.piece_bytes, 1)};
  slot.run_count = static_cast<uint32_t>(plan_runs(slot.parts, into, whole.dst.size(), whole.need, skip, limits, slot.runs));
  slot.checked_on_read = false;  // the workers check the chunks (read once, checked once)
  uint64_t asked = 0;
  for (const ByteRun& r : slot.runs) asked += r.length;
  counters_.runs_read.fetch_add(slot.run_count, kRelaxed);
  counters_.run_bytes_asked.fetch_add(asked, kRelaxed);
  ReadTarget target = whole;
  target.record = whole.record.first(record_bytes);
  target.by_chunks = false;
  target.by_runs = true;
  return target;
}

}  // namespace sluice::runtime::detail
