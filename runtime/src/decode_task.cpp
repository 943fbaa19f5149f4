// Decode workers: the chunks of one frame in parallel (several frames are in
// flight at once, one TBB task each), written straight into the frame's
// buffers. The worker that finishes the last chunk publishes the frame.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <chrono>

#include "pipeline_core.h"
#include "sluice/io/codec.h"
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

bool PipelineCore::stale(const Slot& slot) const {
  return stopping_.load(kRelaxed) || slot.abandoned.load(kRelaxed) || generation_.load(kRelaxed) != slot.generation;
}

void PipelineCore::decode_frame(Slot& slot, uint32_t s) noexcept {
  const size_t chunks = slot.header.chunks.size();
  try {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t c = range.begin(); c != range.end(); ++c) {
        decode_chunk(slot, c);
        // The last chunk publishes the frame; nothing here touches the slot
        // after that (every chunk is done, so the loop is over).
        if (slot.chunks_left.fetch_sub(1, std::memory_order_acq_rel) == 1) finish_decode(s);
      }
    });
  } catch (...) {
    // TBB could not run the chunks (no memory for its tasks); it waited for
    // those that ran. The frame fails, and is finished here unless its last
    // chunk finished it.
    claim_error(slot, [&] { return FrameError{reader_.location(slot.frame), "no memory to decode the frame"}; });
    if (slot.chunks_left.exchange(0, std::memory_order_acq_rel) > 0) finish_decode(s);
  }
}

void PipelineCore::decode_chunk(Slot& slot, size_t c) noexcept {
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
    if (options_.faults.before_decode_chunk) options_.faults.before_decode_chunk(slot.frame, c);
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
      io::decode_chunk(slot.record_bytes, chunk, reader_.header(), destination, scratch, slot.where);
    }
  } catch (const io::Error& e) {
    claim_error(slot, [&] {
      FrameError error = FrameError::from(e);
      if (!error.where.chunk) error.where.chunk = c;
      return error;
    });
    return;
  } catch (const std::exception& e) {
    claim_error(slot, [&] { return FrameError{reader_.location(slot.frame, c), e.what()}; });
    return;
  } catch (...) {
    claim_error(slot, [&] { return FrameError{reader_.location(slot.frame, c), "unknown exception while decoding"}; });
    return;
  }
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count();
  const uint64_t bytes = slot.layout.encoded_bytes > 0 ? chunk.compressed_size
                         : world()                      ? uint64_t(chunk.particle_count) * stride
                                                        : uint64_t(chunk.particle_count) * (stride + 2 * uint64_t(attribute_streams_));
  const int worker = tbb::this_task_arena::current_thread_index();
  if (worker >= 0 && uint32_t(worker) < worker_slots()) {
    WorkerCounters& w = workers_[uint32_t(worker)];
    w.chunks.fetch_add(1, kRelaxed);
    w.output_bytes.fetch_add(bytes, kRelaxed);
    w.busy_ns.fetch_add(static_cast<uint64_t>(ns), kRelaxed);
  }
  counters_.decoded_bytes.fetch_add(bytes, kRelaxed);
}

void PipelineCore::convert_chunk(Slot& slot, size_t c, io::DecodeScratch& scratch) {
  // Per worker: one chunk's decoded particles and attribute streams, which
  // stay in its cache between the decode and the conversion.
  thread_local std::vector<std::byte> decoded;
  thread_local std::vector<std::vector<uint16_t>> streams;
  thread_local std::vector<uint16_t*> targets;
  thread_local std::vector<const uint16_t*> sources;
  const io::ChunkDesc& chunk = slot.header.chunks[c];
  const io::FileHeader& file = reader_.header();
  const size_t n = chunk.particle_count;
  decoded.resize(n * io::decoded_particle_bytes(file.position_coding));
  streams.resize(attribute_streams_);
  targets.assign(stream_of_attribute_.size(), nullptr);
  sources.clear();
  for (uint32_t k = 0; k < attribute_streams_; ++k) {
    streams[k].resize(n);
    targets[attribute_of_stream_[k]] = streams[k].data();
    sources.push_back(streams[k].data());
  }
  io::decode_chunk(slot.record_bytes, chunk, file, io::ChunkDestination{decoded, targets}, scratch, slot.where);
  io::convert_chunk(chunk, decoded, sources, file.position_coding, attribute_of_stream_, slot.header.particle_count,
                    slot.chunk_first[c], slot.world);
}

void PipelineCore::finish_decode(uint32_t s) {
  Slot& slot = slots_[s];
  SlotState result = SlotState::Ready;
  if (slot.error_claimed.load(std::memory_order_acquire)) result = SlotState::Failed;
  else if (slot.skipped.load(kRelaxed)) result = SlotState::Cancelled;
  switch (result) {
    case SlotState::Ready: counters_.frames_decoded.fetch_add(1, kRelaxed); break;
    case SlotState::Failed: counters_.frames_failed.fetch_add(1, kRelaxed); break;
    default: counters_.frames_cancelled.fetch_add(1, kRelaxed); break;
  }
  // The record is no longer needed once every chunk is done with it.
  if (!record_returns_.try_push(slot.record)) std::terminate();  // holds every record buffer
  slot.record = kNoRecord;
  frames_decoding_.fetch_sub(1, std::memory_order_release);
  slot.state.store(result, std::memory_order_release);
  slot.state.notify_all();  // a consumer may be waiting for this frame
  wake_reader();            // the record buffer, or a drained slot, is free
}

}  // namespace sluice::runtime::detail
