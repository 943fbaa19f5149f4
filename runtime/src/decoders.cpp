#include "decoders.h"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <array>
#include <chrono>

#include <exception>

#include "sluice/io/gpu_decode_plan.h"

namespace sluice::runtime::detail {
namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

// Scratch for a thread outside the arena's slots (made on its first use only).
io::DecodeScratch& outside_scratch() {
  thread_local io::DecodeScratch scratch;
  return scratch;
}

}  // namespace

Decoders::Decoders(Parts parts)
    : parts_(std::move(parts)),
      record_returns_(parts_.records),
      scratch_(std::make_unique<io::DecodeScratch[]>(worker_slots())),  // made here, not on a worker's first chunk
      workers_(std::make_unique<WorkerCounters[]>(worker_slots())) {
  // TBB workers wanted: every decode slot (the read helpers are threads of
  // their own, read_crew.h).
  if (parts_.threads + 1 > tbb::info::default_concurrency()) {
    parallelism_.emplace(tbb::global_control::max_allowed_parallelism, size_t(parts_.threads) + 1);
  }
  arena_.initialize(parts_.threads, 0);  // no slot reserved: only workers decode
}

void Decoders::wait() noexcept {
  // Waited for from outside the arena: the workers finish them.
  try {
    group_.wait();
  } catch (...) {
    // Decode tasks catch everything themselves; nothing may leave a destructor.
  }
}

void Decoders::prepare(Slot& slot) {
  slot.chunks_left.store(static_cast<uint32_t>(slot.header.chunks.size()), kRelaxed);
  frames_decoding_.fetch_add(1, kRelaxed);
}

void Decoders::start(Slot& slot, uint32_t s) noexcept {
  try {
    if (parts_.options->faults.before_decode_handoff) parts_.options->faults.before_decode_handoff(slot.frame);
    arena_.enqueue(group_.defer([this, &slot, s] { decode_frame(slot, s); }));
  } catch (...) {
    // The frame could not be handed to the workers (no memory for the
    // task): it fails, in its place, as a decode would have failed it.
    claim_error(slot, [&] { return FrameError{parts_.reader->location(slot.frame), "no memory to hand the frame to the decoders"}; });
    slot.chunks_left.store(0, kRelaxed);
    finish(s);
  }
}

void Decoders::add_stats(PipelineStats& stats) const {
  for (uint32_t w = 0; w < worker_slots(); ++w) {
    const WorkerCounters& wc = workers_[w];
    const uint64_t chunks = wc.chunks.load(kRelaxed);
    if (chunks == 0) continue;
    stats.workers.push_back({w, chunks, wc.output_bytes.load(kRelaxed), double(wc.busy_ns.load(kRelaxed)) * 1e-9});
  }
}

bool Decoders::stale(const Slot& slot) const {
  return parts_.stopping->load(kRelaxed) || slot.abandoned.load(kRelaxed) ||
         parts_.generation->load(kRelaxed) != slot.generation;
}

void Decoders::decode_frame(Slot& slot, uint32_t s) noexcept {
  const size_t chunks = slot.header.chunks.size();
  try {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t c = range.begin(); c != range.end(); ++c) {
        decode_chunk(slot, c);
        // The last chunk publishes the frame; nothing here touches the slot
        // after that (every chunk is done, so the loop is over).
        if (slot.chunks_left.fetch_sub(1, std::memory_order_acq_rel) == 1) finish(s);
      }
    });
  } catch (...) {
    // TBB could not run the chunks (no memory for its tasks); it waited for
    // those that ran. The frame fails, and is finished here unless its last
    // chunk finished it.
    claim_error(slot, [&] { return FrameError{parts_.reader->location(slot.frame), "no memory to decode the frame"}; });
    if (slot.chunks_left.exchange(0, std::memory_order_acq_rel) > 0) finish(s);
  }
}

void Decoders::decode_chunk(Slot& slot, size_t c) noexcept {
  if (stale(slot)) {  // a newer schedule, or the consumer dropped it: skip, do not wait
    slot.skipped.store(true, kRelaxed);
    return;
  }
  if (slot.error_claimed.load(kRelaxed)) return;  // the frame has failed already
  const io::ChunkDesc& chunk = slot.header.chunks[c];
  const uint64_t first = slot.chunk_first[c];
  const size_t stride = slot.layout.particle_stride;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (parts_.options->faults.before_decode_chunk) parts_.options->faults.before_decode_chunk(slot.frame, c);
    // Each arena slot has its scratch (a thread outside the arena, which TBB
    // does not let decode here, would get one of its own).
    const int worker = tbb::this_task_arena::current_thread_index();
    io::DecodeScratch& scratch = worker >= 0 && uint32_t(worker) < worker_slots() ? scratch_[uint32_t(worker)] : outside_scratch();
    // The slot's location names the file and frame without an allocation per
    // chunk; the chunk is added to the error below.
    if (world()) {
      convert_chunk(slot, c, scratch);
    } else if (slot.layout.encoded_bytes > 0) {  // kept encoded: the GPU decodes it
      // Checked on read: the bytes were hashed as they were copied in.
      io::stage_chunk(slot.record_bytes, slot.header, slot.plan, c, slot.buffers.particles, !slot.checked_on_read,
                      slot.where);
    } else {
      std::array<uint16_t*, io::kMaxAttributes> targets{};
      for (size_t a = 0; a < slot.attribute_targets.size(); ++a) {
        if (slot.attribute_targets[a]) targets[a] = slot.attribute_targets[a] + first;
      }
      const io::ChunkDestination destination{
          slot.buffers.particles.subspan(first * stride, size_t(chunk.particle_count) * stride),
          std::span<uint16_t* const>(targets.data(), slot.attribute_targets.size())};
      io::decode_chunk(slot.record_bytes, chunk, parts_.reader->header(), destination, scratch, slot.where);
    }
  } catch (const io::Error& e) {
    claim_error(slot, [&] {
      FrameError error = FrameError::from(e);
      if (!error.where.chunk) error.where.chunk = c;
      return error;
    });
    return;
  } catch (const std::exception& e) {
    claim_error(slot, [&] { return FrameError{parts_.reader->location(slot.frame, c), e.what()}; });
    return;
  } catch (...) {
    claim_error(slot, [&] { return FrameError{parts_.reader->location(slot.frame, c), "unknown exception while decoding"}; });
    return;
  }
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count();
  const uint64_t bytes = slot.layout.encoded_bytes > 0 ? uint64_t(chunk.compressed_size) + (chunk.fine.read() ? chunk.fine.size : 0)
                         : world()                      ? uint64_t(chunk.particle_count) * stride
                                                        : uint64_t(chunk.particle_count) * (stride + 2 * uint64_t(parts_.attribute_of_stream.size()));
  const int worker = tbb::this_task_arena::current_thread_index();
  if (worker >= 0 && uint32_t(worker) < worker_slots()) {
    WorkerCounters& w = workers_[uint32_t(worker)];
    w.chunks.fetch_add(1, kRelaxed);
    w.output_bytes.fetch_add(bytes, kRelaxed);
    w.busy_ns.fetch_add(static_cast<uint64_t>(ns), kRelaxed);
  }
  parts_.counters->decoded_bytes.fetch_add(bytes, kRelaxed);
}

void Decoders::convert_chunk(Slot& slot, size_t c, io::DecodeScratch& scratch) {
  // Per worker: one chunk's decoded particles and attribute streams, which
  // stay in its cache between the decode and the conversion.
  thread_local std::vector<std::byte> decoded;
  thread_local std::vector<std::vector<uint16_t>> streams;
  thread_local std::vector<uint16_t*> targets;
  thread_local std::vector<const uint16_t*> sources;
  const io::ChunkDesc& chunk = slot.header.chunks[c];
  const io::FileHeader& file = parts_.reader->header();
  const size_t n = chunk.particle_count;
  decoded.resize(n * io::decoded_particle_bytes(file.position_coding));
  const std::vector<size_t>& attribute_of = parts_.attribute_of_stream;
  streams.resize(attribute_of.size());
  targets.assign(parts_.stream_of_attribute.size(), nullptr);
  sources.clear();
  for (size_t k = 0; k < attribute_of.size(); ++k) {
    streams[k].resize(n);
    targets[attribute_of[k]] = streams[k].data();
    sources.push_back(streams[k].data());
  }
  io::decode_chunk(slot.record_bytes, chunk, file, io::ChunkDestination{decoded, targets}, scratch, slot.where);
  io::convert_chunk(chunk, decoded, sources, file.position_coding, attribute_of, slot.header.particle_count,
                    slot.chunk_first[c], slot.world);
}

void Decoders::finish(uint32_t s) {
  Slot& slot = parts_.slots[s];
  SlotState result = SlotState::Ready;
  if (slot.error_claimed.load(std::memory_order_acquire)) result = SlotState::Failed;
  else if (slot.skipped.load(kRelaxed)) result = SlotState::Cancelled;
  switch (result) {
    case SlotState::Ready: parts_.counters->frames_decoded.fetch_add(1, kRelaxed); break;
    case SlotState::Failed: parts_.counters->frames_failed.fetch_add(1, kRelaxed); break;
    default: parts_.counters->frames_cancelled.fetch_add(1, kRelaxed); break;
  }
  // The record is no longer needed once every chunk is done with it.
  if (!record_returns_.try_push(slot.record)) std::terminate();  // holds every record buffer
  slot.record = kNoRecord;
  frames_decoding_.fetch_sub(1, std::memory_order_release);
  slot.state.store(result, std::memory_order_release);
  slot.state.notify_all();  // a consumer may be waiting for this frame
  wake(*parts_.reader_wake);  // the record buffer, or a drained slot, is free
}

}  // namespace sluice::runtime::detail
