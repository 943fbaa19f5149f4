// Construction, the consumer's side of the pipeline, and stats.
#include <tbb/info.h>

#include <algorithm>
#include <exception>
#include <stdexcept>
#include <string>
#include <utility>

#include "pipeline_core.h"
#include "sluice/error.h"

namespace sluice::runtime {

ThreadSplit default_thread_split(int cores, DecodeMode mode) {
  const bool kept_encoded = mode == DecodeMode::KeepEncoded;
  cores = std::max(cores, 1);
  ThreadSplit split;
  if (kept_encoded) {
    split.read = std::clamp(cores * 13 / 16, 1, 13);
    split.decode = std::max(1, cores - split.read);
    return split;
  }
  // World frames cost the workers more per chunk (the conversion to float
  // arrays) for the same bytes read: half as many readers.
  split.read = std::clamp(mode == DecodeMode::World ? cores / 8 : cores / 4, 1, 4);
  split.decode = cores >= 8 ? cores - split.read : cores;
  return split;
}

namespace detail {
namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

std::vector<uint32_t> stream_map(const io::ContainerReader& reader, const std::optional<std::vector<uint32_t>>& wanted,
                                 uint32_t& streams) {
  const size_t count = reader.header().attributes.size();
  std::vector<uint32_t> map(count, ~0u);
  streams = 0;
  if (!wanted) {
    for (size_t a = 0; a < count; ++a) map[a] = streams++;
    return map;
  }
  for (uint32_t a : *wanted) {
    if (a >= count) {
      throw io::Error({reader.path()}, "no attribute " + std::to_string(a) + " to decode (the file has " +
                                           std::to_string(count) + ")");
    }
    if (map[a] != ~0u) throw io::Error({reader.path()}, "attribute " + std::to_string(a) + " asked for twice");
    map[a] = streams++;
  }
  return map;
}

uint32_t most_chunks_of(const io::ContainerReader& reader) {
  uint32_t most = 0;
  for (const io::FrameIndexEntry& e : reader.index().frames) most = std::max(most, e.chunk_count);
  return most;
}

}  // namespace

PipelineCore::PipelineCore(const io::ContainerReader& reader, FrameAllocator& allocator, PipelineOptions options)
    : reader_(reader),
      allocator_(allocator),
      options_(std::move(options)),
      most_chunks_(most_chunks_of(reader_)),
      decode_threads_(options_.decode.threads > 0 ? options_.decode.threads
                                                  : default_thread_split(tbb::info::default_concurrency(), options_.decode.mode).decode),
      slot_count_(std::max<uint32_t>(2, options_.window.budget.ring_capacity)),
      slots_(std::make_unique<Slot[]>(slot_count_)),
      delivery_({slots_.get(), slot_count_, &counters_, &reader_wake_, &reader_failed_}),
      records_(size_t(decode_threads_) + 1),
      demand_(options_.demand, counters_, most_chunks_) {
  if ((options_.decode.mode == DecodeMode::KeepEncoded)) {
    if (!io::gpu_decodable(reader_.header())) {
      throw io::Error({reader_.path()}, "frames cannot stay encoded for the GPU: its positions are float32");
    }
  }
  const std::optional<std::vector<uint32_t>> none = std::vector<uint32_t>{};  // encoded: nothing decoded on the CPU
  stream_of_attribute_ = stream_map(reader_, (options_.decode.mode == DecodeMode::KeepEncoded) ? none : options_.decode.attributes, attribute_streams_);
  attribute_of_stream_.resize(attribute_streams_);
  for (size_t a = 0; a < stream_of_attribute_.size(); ++a) {
    if (stream_of_attribute_[a] != ~0u) attribute_of_stream_[stream_of_attribute_[a]] = a;
  }
  const bool world = options_.decode.mode == DecodeMode::World;
  footprint_ = world ? largest_frame(reader_, 0, &allocator_, options_.layers, false,
                                     uint32_t(io::world_particle_bytes(attribute_streams_)))
                     : largest_frame(reader_, attribute_streams_, &allocator_, options_.layers,
                                     options_.decode.mode == DecodeMode::KeepEncoded);
  record_where_.file = reader_.path();
  decoders_.emplace(Decoders::Parts{slots_.get(), &reader_, &options_, &counters_, &stopping_, &generation_, &reader_wake_,
                                    decode_threads_, records_.size(), stream_of_attribute_, attribute_of_stream_});

  // Readers come out of the cores by default; with a worker count given they
  // come on top of it: a quarter as many (1 to 4).
  RecordReads::Parts reads;
  reads.reader = &reader_;
  reads.options = &options_;
  reads.counters = &counters_;
  reads.stopping = &stopping_;
  reads.generation = &generation_;
  reads.source = options_.read.source ? options_.read.source
                                      : std::make_shared<FileRecordSource>(reader_.path(), reader_.descriptor(),
                                                                           options_.read.direct_io, options_.read.mapped);
  if (options_.decode.mode == DecodeMode::KeepEncoded) reads.relay = allocator_.relay();
  reads.threads = options_.read.threads > 0    ? options_.read.threads
                  : options_.decode.threads > 0 ? std::clamp(decode_threads_ / 4, 1, 4)
                                                : default_thread_split(tbb::info::default_concurrency(), options_.decode.mode).read;
  reads.rounds = options_.read.rounds;
  reads_.emplace(std::move(reads));

  initial_plan_ = SlotWindow::plan(window_parts(), allocator_.kept_bytes());  // blocks a previous pipeline left for reuse count as ours
  // Chunk tables sized for the file's largest frame in the slots a window of
  // this plan cycles through (the reader takes free slots last-in first-out);
  // others get theirs at first use. Parsing a record then never allocates.
  const uint32_t warm_slots = std::min<uint32_t>(slot_count_, 2 * initial_plan_.frames + 8);
  for (uint32_t s = 0; s < warm_slots; ++s) {
    slots_[s].header.chunks.reserve(most_chunks_);
    slots_[s].chunk_first.reserve(most_chunks_);
    slots_[s].attribute_targets.reserve(reader_.header().attributes.size());
    slots_[s].where.file = reader_.path();
  }
  counters_.window_frames.store(initial_plan_.frames, kRelaxed);
  counters_.active_frames.store(SlotWindow::initial_active(window_parts(), initial_plan_), kRelaxed);
  counters_.record_buffers.store(initial_plan_.record_buffers, kRelaxed);
  if (options_.window.on_change) options_.window.on_change({0, initial_plan_});

  reader_thread_ = std::thread([this] { reader_main(); });
}

PipelineCore::~PipelineCore() {
  stopping_.store(true, std::memory_order_release);
  wake_reader();
  if (reader_thread_.joinable()) reader_thread_.join();
  // Decode tasks still running see stopping_ and skip their remaining chunks.
  decoders_->wait();
  for (uint32_t s = 0; s < slot_count_; ++s) {
    if (slots_[s].has_buffers) allocator_.release(slots_[s].buffers);
  }
}

uint64_t PipelineCore::restart(const PlaybackSchedule& schedule) {
  if (schedule.frame_count > reader_.frame_count() || schedule.stride == 0 ||
      (schedule.direction != 1 && schedule.direction != -1)) {
    throw Error("Pipeline::restart(): the schedule needs frame_count <= the file's frames (" +
                                std::to_string(reader_.frame_count()) + "), stride >= 1 and direction +1 or -1");
  }
  uint64_t g;
  {
    const std::lock_guard lock(control_mutex_);
    requested_ = schedule;
    g = generation_.load(kRelaxed) + 1;
    generation_.store(g, std::memory_order_release);
  }
  delivery_.begin(schedule, g);
  wake_reader();
  return g;
}

FrameHandle PipelineCore::take() {
  const Delivery::Taken taken = delivery_.take();
  const Entry& entry = taken.entry;
  FrameHandle h;
  h.frame_ = entry.frame;
  h.generation_ = entry.generation;
  h.sequence_ = entry.sequence;
  if (taken.state == SlotState::Failed) {
    const Slot& slot = slots_[entry.slot];
    h.error_ = std::make_unique<FrameError>(slot.error);
    if (h.error_->message.empty()) h.error_->message = "failed, and there was no memory left to say why";
    // Errors count chunks among those read: name the file's record, and its
    // LOD tier where the file has tiers.
    std::optional<uint64_t>& chunk = h.error_->where.chunk;
    if (slot.demand_applied && chunk && *chunk < slot.header.chunks.size()) {
      const io::ChunkDesc& c = slot.header.chunks[*chunk];
      chunk = c.index;
      if (c.tier > 0 || c.continues_cell) h.error_->message += " (LOD tier " + std::to_string(c.tier) + " of its cell)";
    }
    delivery_.give_back(entry.slot);
  } else {
    slots_[entry.slot].state.store(SlotState::Shown, kRelaxed);
    delivery_.hold();
    h.owner_ = this;
    h.slot_ = entry.slot;
    counters_.frames_delivered.fetch_add(1, kRelaxed);
  }
  return h;
}

PipelineStats PipelineCore::stats() const {
  PipelineStats s;
  s.elapsed_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  const int threads = reads_->threads();
  s.io_mode = reads_->source().describe() + (threads > 1 ? ", " + std::to_string(threads) + " read threads" : "");
  const Counters& c = counters_;
  s.bytes_read = c.bytes_read.load(kRelaxed);
  s.read_seconds = double(reads_->read_ns_now()) * 1e-9;
  s.read_thread_seconds = double(reads_->thread_busy_ns()) * 1e-9;
  s.read_threads = static_cast<uint32_t>(threads);
  s.frames_read = c.frames_read.load(kRelaxed);
  s.record_bytes = c.record_bytes.load(kRelaxed);
  s.frames_by_demand = c.frames_by_demand.load(kRelaxed);
  s.runs_read = c.runs_read.load(kRelaxed);
  s.run_bytes = c.run_bytes_asked.load(kRelaxed);
  s.frames_in_place = c.frames_in_place.load(kRelaxed);
  s.frames_relayed = c.frames_relayed.load(kRelaxed);
  s.relay.claim_seconds = double(c.relay_claim_ns.load(kRelaxed)) * 1e-9;
  s.relay.copy_seconds = double(c.relay_copy_ns.load(kRelaxed)) * 1e-9;
  s.relay.check_seconds = double(c.relay_check_ns.load(kRelaxed)) * 1e-9;
  s.relay.plan_seconds = double(c.relay_plan_ns.load(kRelaxed)) * 1e-9;
  s.relay.send_seconds = double(c.relay_send_ns.load(kRelaxed)) * 1e-9;
  s.cache_hits = c.cache_hits.load(kRelaxed);
  s.frames_decoded = c.frames_decoded.load(kRelaxed);
  s.decoded_bytes = c.decoded_bytes.load(kRelaxed);
  s.frames_cancelled = c.frames_cancelled.load(kRelaxed);
  s.frames_delivered = c.frames_delivered.load(kRelaxed);
  s.frames_failed = c.frames_failed.load(kRelaxed);
  s.generation = generation_.load(kRelaxed);
  s.window_frames = c.window_frames.load(kRelaxed);
  s.active_frames = c.active_frames.load(kRelaxed);
  s.record_buffers = c.record_buffers.load(kRelaxed);
  s.frames_ready = c.frames_ready.load(kRelaxed);
  s.held_bytes = c.held_bytes.load(kRelaxed);
  s.peak_record_bytes = c.peak_record_bytes.load(kRelaxed);
  decoders_->add_stats(s);
  return s;
}

}  // namespace detail

// --- FrameHandle ---

FrameHandle::FrameHandle(FrameHandle&& other) noexcept { *this = std::move(other); }

FrameHandle& FrameHandle::operator=(FrameHandle&& other) noexcept {
  if (this == &other) return *this;
  reset();
  owner_ = std::exchange(other.owner_, nullptr);
  slot_ = other.slot_;
  frame_ = other.frame_;
  generation_ = other.generation_;
  sequence_ = other.sequence_;
  error_ = std::move(other.error_);
  return *this;
}

void FrameHandle::reset() {
  if (owner_) std::exchange(owner_, nullptr)->release(slot_);
  error_.reset();
}

void FrameHandle::spoil() {
  if (owner_) owner_->spoil(slot_);
}

const io::FrameHeader& FrameHandle::header() const { return owner_->slot(slot_).header; }
std::span<const uint64_t> FrameHandle::chunk_first() const { return owner_->slot(slot_).chunk_first; }
const FrameLayout& FrameHandle::layout() const { return owner_->slot(slot_).layout; }
const FrameBuffers& FrameHandle::buffers() const { return owner_->slot(slot_).buffers; }
FrameContent FrameHandle::content() const {
  if (!gpu_plan()) return owner_->world() ? FrameContent::World : FrameContent::Decoded;
  return layout().resident ? FrameContent::Relayed : FrameContent::Encoded;
}
const io::GpuDecodePlan* FrameHandle::gpu_plan() const {
  const Slot& s = owner_->slot(slot_);
  return s.layout.encoded_bytes > 0 ? &s.plan : nullptr;
}

// --- Pipeline ---

Pipeline::Pipeline(const io::ContainerReader& reader, FrameAllocator& allocator, PipelineOptions options)
    : core_(std::make_unique<detail::PipelineCore>(reader, allocator, std::move(options))) {}
Pipeline::~Pipeline() = default;

uint64_t Pipeline::restart(const PlaybackSchedule& schedule) { return core_->restart(schedule); }
const PlaybackSchedule& Pipeline::schedule() const { return core_->delivery_.schedule(); }
uint64_t Pipeline::generation() const { return core_->delivery_.generation(); }
NextEntry Pipeline::peek(size_t i) { return core_->delivery_.peek(i); }
NextEntry Pipeline::wait_next() { return core_->delivery_.wait_next(); }
FrameHandle Pipeline::take() { return core_->take(); }
void Pipeline::drop() { core_->delivery_.drop(); }
uint32_t Pipeline::ready_count() { return core_->delivery_.ready_count(); }
PipelineStats Pipeline::stats() const { return core_->stats(); }
uint32_t Pipeline::window() const { return core_->counters_.window_frames.load(std::memory_order_relaxed); }
uint32_t Pipeline::most_ahead() const { return detail::ahead_most(window()); }
std::string Pipeline::io_mode() const { return core_->stats().io_mode; }
const io::ContainerReader& Pipeline::reader() const { return core_->reader_; }
std::optional<FrameError> Pipeline::fatal_error() const {
  if (!core_->reader_failed_.load(std::memory_order_acquire)) return std::nullopt;
  return core_->fatal_;
}

void Pipeline::set_demand(const ViewDemand& demand) {
  // No wake: the reader takes it when it next starts a frame, whatever
  // woke it (players call this every displayed frame).
  core_->demand_.set(demand);
}

bool Pipeline::short_of(const FrameHandle& frame, const ViewDemand& demand) const {
  if (frame.empty() || frame.failed()) return false;
  const Slot& slot = core_->slot(frame.slot_);
  return slot.demand_applied && runtime::short_of(demand, slot.cells, slot.header.blob_voxel);
}

}  // namespace sluice::runtime
