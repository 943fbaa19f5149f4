// The reader thread: follows the schedule, keeps the window, reads records
// and hands frames to the decode workers. It owns every slot that is not out
// with the consumer or being decoded, so its bookkeeping (ReaderState) needs
// no synchronisation; everything it learns from other threads arrives
// through the return rings, slot states and the generation number.
#include <algorithm>
#include <cstring>
#include <exception>

#include "pipeline_core.h"

namespace sluice::runtime::detail {
namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

}  // namespace

SlotWindow::Parts PipelineCore::window_parts() {
  SlotWindow::Parts p;
  p.slots = slots_.get();
  p.slot_count = slot_count_;
  p.records = &records_;
  p.allocator = &allocator_;
  p.counters = &counters_;
  p.options = &options_.window;
  p.footprint = footprint_;
  p.file_frames = reader_.frame_count();
  p.decode_threads = decode_threads_;
  p.frames_decoding = &decoders_->in_flight();
  return p;
}

void PipelineCore::reader_main() {
  ReaderState rs(window_parts(), initial_plan_, reads_->rounds());  // the plan the constructor reported
  try {
    while (true) {
      // The wake count is read before anything it guards, stopping_ too: a
      // stop that came between reading stopping_ and the count was lost
      // before, and the destructor's join waited for ever (TSan run, CI).
      const uint32_t seen = reader_wake_.load(std::memory_order_acquire);
      if (stopping_.load(std::memory_order_acquire)) break;
      if (!reader_iteration(rs)) reader_wake_.wait(seen, std::memory_order_acquire);
    }
  } catch (const std::exception& e) {
    // Only the thread's own bookkeeping gets here (frame errors become
    // failed entries): tell the consumer nothing more will come.
    fatal_ = {{reader_.path()}, std::string("the reader thread stopped: ") + e.what()};
    reader_failed_.store(true, std::memory_order_release);
    delivery_.wake_consumer();
  }
  // Reads still running write into buffers this thread accounts for, and
  // their rounds live in `rs`: they end here (stopping: their pieces are
  // skipped).
  reads_->drain();
}

bool PipelineCore::reader_iteration(ReaderState& rs) {
  collect_returns(rs);
  rs.window.take_record_returns(decoders_->record_returns());
  adopt_schedule(rs);
  rs.window.reevaluate_if_due();
  // A record read in the background whose buffers come after it is parsed
  // (CPU decoding) will take one of the kept ones: it counts as free here.
  uint32_t unbuffered = 0;
  for (uint32_t i = 0; i < rs.pending.size(); ++i) unbuffered += !slots_[rs.pending.at(i).slot].has_buffers;
  rs.window.shrink(rs.in_flight(), unbuffered);
  // Nothing more to start: the record read in the background is finished
  // now, not when the next one begins.
  const auto frame = rs.schedule.frame_at(rs.next_k);
  if (!frame) return settle_pending(rs);
  if (rs.in_flight() >= rs.window.ahead_limit()) {
    if (!rs.window.grow()) return settle_pending(rs);
    return true;  // grown: measured again against the larger limit (never past ahead_most of the window)
  }
  switch (start_entry(rs, rs.next_k, *frame)) {
    case Start::Pushed: ++rs.next_k; return true;
    case Start::Cancelled: return true;  // a newer schedule is waiting
    case Start::Blocked: return settle_pending(rs);
  }
  return false;
}

void PipelineCore::adopt_schedule(ReaderState& rs) {
  if (generation_.load(std::memory_order_acquire) == rs.generation) return;
  // Reads of the old schedule still running end first (their pieces see the
  // new generation and stop), so that what they publish, if anything, is
  // told apart as stale.
  settle_all_pending(rs);
  {
    const std::lock_guard lock(control_mutex_);
    rs.schedule = requested_;
    rs.generation = generation_.load(kRelaxed);
  }
  rs.next_k = 0;
  // Kernel readahead only helps going forward one frame at a time, and
  // only where frames are read whole: past a frame's wanted prefix it reads
  // the layers left out (the interior), which no later read wants. Prefix
  // reads are asked for exactly (will_need) instead.
  const bool whole = reader_.frame_count() == 0 || !reads_prefix(reader_.index().frames.front());
  const bool sequential = whole && rs.schedule.direction > 0 && rs.schedule.stride == 1;
  reads_->source().set_access(sequential ? AccessPattern::Sequential : AccessPattern::Random);
}

void PipelineCore::collect_returns(ReaderState& rs) {
  uint32_t s;
  while (delivery_.take_return(s)) {
    --rs.out;
    rs.window.returned(s);
  }
  rs.window.settle_drained();
}

PipelineCore::Start PipelineCore::start_entry(ReaderState& rs, uint64_t k, uint64_t frame) {
  // A decoded copy kept behind the playhead (the newest, if several).
  if (const auto hit = rs.window.take_cached(frame)) {
    const uint32_t s = *hit;
    if (demand_.short_of(slots_[s])) {
      rs.window.free_slot(s);  // read for a smaller demand than today's: read it again (refinement)
    } else {
      settle_all_pending(rs);  // entries go out in schedule order
      slots_[s].generation = rs.generation;
      slots_[s].state.store(SlotState::Ready, std::memory_order_release);
      counters_.cache_hits.fetch_add(1, kRelaxed);
      publish(rs, s, k);
      return Start::Pushed;
    }
  }

  const auto claimed = rs.window.claim(rs.in_flight());
  if (!claimed) return Start::Blocked;
  const uint32_t s = claimed->slot, record = claimed->record;
  Slot& slot = slots_[s];
  slot.frame = frame;
  slot.spoiled = false;
  slot.generation = rs.generation;
  slot.record = record;
  slot.abandoned.store(false, kRelaxed);
  slot.skipped.store(false, kRelaxed);
  slot.error_claimed.store(false, kRelaxed);
  slot.state.store(SlotState::Reading, kRelaxed);
  rs.window.count_started();

  // Whether this frame is read by the demand, decided once (set_demand may
  // change the latest demand while it is read).
  const bool by_demand = demand_.leaves_out();
  // Ask the kernel for the next entry's bytes while this one is read: the
  // whole record when it is read whole, else its table (what else it needs
  // is hinted once the table is parsed: read_table), so that storage reads
  // no bytes the frame leaves out.
  if (const auto next = rs.schedule.frame_at(k + 1)) {
    const io::FrameIndexEntry& e = reader_.index().frames[*next];
    const bool whole = !reads_in_place() && !reads_prefix(e) && !by_demand;
    reads_->source().will_need(e.offset, whole ? e.bytes : io::frame_table_bytes(e.chunk_count, reader_.header().attributes.size()));
  }

  ReadTarget target;
  try {
    if (slot.header.chunks.capacity() < most_chunks_) {  // a slot's first use: room for any frame of the file
      slot.header.chunks.reserve(most_chunks_);
      slot.chunk_first.reserve(most_chunks_);
      slot.parts.reserve(size_t(most_chunks_));  // a fine part is a table record too: most_chunks_ counts both
      slot.piece_cuts.reserve(size_t(most_chunks_) + 1);
      slot.runs.reserve(2 * size_t(most_chunks_) + 8);
      slot.attribute_targets.reserve(reader_.header().attributes.size());
      slot.where.file = reader_.path();
    }
    // Frames kept encoded and read in place are checked as they are read,
    // chunk by chunk, so their tables come first; relayed, their chunks are
    // planned as they are read too (frame_allocator.h).
    slot.relayed = relays();
    slot.relay_refused.store(false, kRelaxed);
    slot.where.frame = frame;
    target = slot.relayed ? relayed_target(rs, slot, record)
             : reads_in_place() ? staged_target(rs, slot)
                                : record_target(rs, slot, record);
    slot.checked_on_read = reads_in_place();
    slot.demand_applied = false;
    slot.by_demand = by_demand;
    slot.table_parsed = slot.checked_on_read || reads_prefix(reader_.index().frames[frame]) || by_demand;
    if (slot.table_parsed) target = read_table(slot, target);
  } catch (const io::Error& e) {
    settle_all_pending(rs);  // entries go out in schedule order
    finish_read(rs, s, k, ReadOutcome::Failed, FrameError::from(e));
    return Start::Pushed;
  } catch (const std::exception& e) {
    settle_all_pending(rs);
    finish_read(rs, s, k, ReadOutcome::Failed, FrameError{reader_.location(frame), e.what()});
    return Start::Pushed;
  }
  begin_background_read(rs, s, k, target);
  return Start::Pushed;
}

void PipelineCore::begin_background_read(ReaderState& rs, uint32_t s, uint64_t k, const ReadTarget& target) {
  // With every crew round in flight the oldest is joined first; it is
  // finished (parsed, handed to the workers, published) while this one and
  // the others are read.
  FrameError error;
  const bool joined = rs.pending.full();
  const uint32_t joined_slot = rs.pending.oldest().slot;
  const uint64_t joined_k = rs.pending.oldest().k;
  const ReadOutcome outcome = joined ? join_pending(rs, error) : ReadOutcome::Read;

  PendingRead& read = rs.pending.push();
  read.slot = s;
  read.k = k;
  read.record = target.record;
  if (target.by_runs) {
    reads_->begin_runs(read.round, slots_[s], target.dst, target.offset, target.need, rs.generation);
  } else if (target.by_chunks) {
    reads_->begin_chunks(read.round, slots_[s], target.record, target.offset, rs.generation);
  } else {
    reads_->begin_bytes(read.round, target.dst, target.offset, target.need, slots_[s].frame, rs.generation);
  }

  if (joined) finish_read(rs, joined_slot, joined_k, outcome, std::move(error));
}

// Joins the oldest pending read (the crew's oldest round) and takes it off
// the list.
PipelineCore::ReadOutcome PipelineCore::join_pending(ReaderState& rs, FrameError& error) {
  PendingRead& read = rs.pending.oldest();
  Slot& slot = slots_[read.slot];
  const uint64_t frame = slot.frame;
  bool completed = false;
  try {
    completed = reads_->join(read.round);
  } catch (const io::Error& e) {
    rs.pending.pop();
    error = FrameError::from(e);
    return ReadOutcome::Failed;
  } catch (const std::exception& e) {
    rs.pending.pop();
    error = {reader_.location(frame), e.what()};
    return ReadOutcome::Failed;
  }
  const std::span<const std::byte> record = read.record;
  rs.pending.pop();
  if (!completed) return ReadOutcome::Cancelled;
  slot.record_bytes = record;
  counters_.frames_read.fetch_add(1, kRelaxed);
  counters_.record_bytes.fetch_add(reader_.index().frames[frame].bytes, kRelaxed);
  return ReadOutcome::Read;
}

bool PipelineCore::settle_pending(ReaderState& rs) {
  if (rs.pending.size() == 0) return false;
  FrameError error;
  const uint32_t s = rs.pending.oldest().slot;
  const uint64_t k = rs.pending.oldest().k;
  const ReadOutcome outcome = join_pending(rs, error);
  finish_read(rs, s, k, outcome, std::move(error));
  return true;
}

void PipelineCore::settle_all_pending(ReaderState& rs) {
  while (settle_pending(rs)) {
  }
}

void PipelineCore::finish_read(ReaderState& rs, uint32_t s, uint64_t k, ReadOutcome outcome, FrameError error) {
  switch (outcome) {
    case ReadOutcome::Read: finish_entry(rs, s, k); return;
    case ReadOutcome::Cancelled: abandon_read(rs, s); return;
    case ReadOutcome::Failed:
      if (!error.where.frame) error.where = reader_.location(slots_[s].frame);  // the source knows only the file
      fail(rs, s, k, std::move(error));
      return;
  }
}

// A read a newer schedule (or stop) cut short: its slot, buffers and record
// go back; nothing is published.
void PipelineCore::abandon_read(ReaderState& rs, uint32_t s) {
  Slot& slot = slots_[s];
  rs.window.return_record(slot.record);
  slot.record = kNoRecord;
  rs.window.free_slot(s);
}

void PipelineCore::finish_entry(ReaderState& rs, uint32_t s, uint64_t k) {
  Slot& slot = slots_[s];
  const uint64_t frame = slot.frame;
  try {
    record_where_.frame = frame;
    if (!slot.table_parsed) reader_.parse_record(frame, slot.record_bytes, slot.header, record_where_);  // no allocation per frame
    io::keep_layers(slot.header, options_.layers);  // the chunks read (decode checks their payloads lie in the prefix)
    if (!slot.demand_applied) demand_.apply(slot);    // read whole: only the demanded tiers are decoded
    slot.where.frame = frame;  // its file was set with its chunk table
    if (slot.relayed && slot.relay_refused.load(std::memory_order_acquire)) read_again_on_host(rs, slot);
    prepare_decode(rs, slot);
  } catch (const io::Error& e) {
    FrameError error = FrameError::from(e);
    if (!error.where.frame) error.where = reader_.location(frame);  // the source knows only the file
    fail(rs, s, k, std::move(error));
    return;
  } catch (const std::exception& e) {
    fail(rs, s, k, {reader_.location(frame), e.what()});
    return;
  }

  const size_t chunks = slot.header.chunks.size();
  if (chunks == 0 || slot.relayed) {  // an empty frame, or one relayed (checked and planned as read): nothing to do
    rs.window.return_record(slot.record);
    slot.record = kNoRecord;
    counters_.frames_decoded.fetch_add(1, kRelaxed);
    slot.state.store(SlotState::Ready, std::memory_order_release);
    publish(rs, s, k);
    return;
  }
  decoders_->prepare(slot);
  slot.state.store(SlotState::Decoding, std::memory_order_release);
  publish(rs, s, k);
  decoders_->start(slot, s);
}

void PipelineCore::set_layout(Slot& slot, uint64_t particles, uint64_t encoded_bytes) const {
  slot.layout.frame = slot.frame;
  slot.layout.particles = particles;
  if (world()) {  // the attributes are float arrays in the particles' block
    slot.layout.particle_stride = static_cast<uint32_t>(io::world_particle_bytes(attribute_streams_));
    slot.layout.attribute_streams = 0;
  } else {
    slot.layout.particle_stride = static_cast<uint32_t>(io::decoded_particle_bytes(reader_.header().position_coding));
    slot.layout.attribute_streams = attribute_streams_;
  }
  slot.layout.encoded_bytes = encoded_bytes;
  slot.layout.resident = false;
}

// A frame read in place whose planes inflate past its area: a larger area,
// the record copied to its start.
void PipelineCore::move_to_larger_area(ReaderState& rs, Slot& slot, uint64_t staged_bytes) {
  FrameLayout larger = slot.layout;
  larger.encoded_bytes = encoded_block_bytes(staged_bytes);
  FrameBuffers buffers = allocator_.allocate(larger);  // throws: the frame fails, the slot keeps its area
  if (buffers.particles.size() < staged_bytes) {
    allocator_.release(buffers);
    throw io::Error(reader_.location(slot.frame), "the frame allocator returned buffers smaller than the frame");
  }
  std::memcpy(buffers.particles.data(), slot.record_bytes.data(), slot.record_bytes.size());
  rs.window.replace_buffers(slot, larger, buffers);
  slot.record_bytes = buffers.particles.first(slot.record_bytes.size());
}

void PipelineCore::read_again_on_host(ReaderState& rs, Slot& slot) {
  relay_off_ = true;
  rs.window.release_buffers(slot);
  slot.relayed = false;
  slot.checked_on_read = false;  // the workers check the chunks
  const ReadTarget whole = staged_target(rs, slot);  // on this thread (a rare path)
  slot.record_bytes = whole.record;
  if (!slot.by_demand) {
    reads_->read_piece(whole.dst, whole.offset, whole.need, slot.frame, whole.offset + whole.need);
    return;
  }
  // The table and the runs of the records the demand kept (slot.header), no more.
  const uint64_t table = std::min<uint64_t>(whole.need, io::frame_table_bytes(reader_.index().frames[slot.frame].chunk_count,
                                                                             reader_.header().attributes.size()));
  reads_->read_piece(whole.dst.first(table), whole.offset, table, slot.frame, whole.offset + whole.need, true);
  plan_runs(slot.parts, 0, whole.dst.size(), whole.need, table,
            {.align = 1, .gap = kRunGap, .piece = std::max<uint64_t>(options_.read.piece_bytes, 1)}, slot.runs);
  for (const ByteRun& run : slot.runs) {
    reads_->read_piece(whole.dst.subspan(run.at, run.length), whole.offset + run.at, run.required, slot.frame,
               whole.offset + run.at + run.required, true);
  }
}

void PipelineCore::prepare_decode(ReaderState& rs, Slot& slot) {
  const io::FrameHeader& h = slot.header;
  slot.chunk_first.resize(h.chunks.size());
  io::chunk_starts(h, slot.chunk_first);  // parse_record checked that the counts add up to the index's
  if (slot.relayed) {  // planned chunk by chunk as read; the plan's tables travel with it
    io::finish_gpu_plan(slot.plan);
    counters_.frames_in_place.fetch_add(1, kRelaxed);
    counters_.frames_relayed.fetch_add(1, kRelaxed);
    return;
  }
  if (!slot.has_buffers) set_layout(slot, h.particle_count, 0);
  if ((options_.decode.mode == DecodeMode::KeepEncoded)) {  // the tables are read here; the workers stage the payloads
    io::plan_gpu_decode(slot.record_bytes, h, reader_.header(), {.color_attribute = options_.decode.color_attribute},
                        slot.plan, slot.where);
    if (!slot.has_buffers) {
      slot.layout.encoded_bytes = encoded_block_bytes(slot.plan.staged_bytes());
    } else if (slot.buffers.particles.size() < slot.plan.staged_bytes()) {
      move_to_larger_area(rs, slot, slot.plan.staged_bytes());
    } else {
      counters_.frames_in_place.fetch_add(1, kRelaxed);
    }
  }
  if (!slot.has_buffers) rs.window.allocate_buffers(slot);

  const uint32_t streams = slot.layout.attribute_streams;
  bool fits = slot.buffers.particles.size() >= slot.layout.particle_bytes() && slot.buffers.attributes.size() >= streams;
  for (uint32_t a = 0; fits && a < streams; ++a) fits = slot.buffers.attributes[a].size() >= h.particle_count;
  if (!fits) throw io::Error(reader_.location(slot.frame), "the frame allocator returned buffers smaller than the frame");
  if ((options_.decode.mode == DecodeMode::KeepEncoded)) io::write_tables(slot.plan, slot.buffers.particles);
  slot.attribute_targets.assign(stream_of_attribute_.size(), nullptr);
  if (world()) {
    slot.world = io::world_spans(slot.buffers.particles, h.particle_count, attribute_streams_);
    return;
  }
  for (size_t a = 0; a < stream_of_attribute_.size(); ++a) {
    if (stream_of_attribute_[a] != ~0u) slot.attribute_targets[a] = slot.buffers.attributes[stream_of_attribute_[a]].data();
  }
}

void PipelineCore::fail(ReaderState& rs, uint32_t s, uint64_t k, FrameError error) {
  Slot& slot = slots_[s];
  slot.error = std::move(error);
  if (slot.record != kNoRecord) {
    rs.window.return_record(slot.record);
    slot.record = kNoRecord;
  }
  counters_.frames_failed.fetch_add(1, kRelaxed);
  slot.state.store(SlotState::Failed, std::memory_order_release);
  publish(rs, s, k);
}

void PipelineCore::publish(ReaderState& rs, uint32_t s, uint64_t k) {
  delivery_.publish({s, slots_[s].generation, k, slots_[s].frame});
  ++rs.out;
}

}  // namespace sluice::runtime::detail
