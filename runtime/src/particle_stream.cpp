#include "sluice/runtime/particle_stream.h"

#include <algorithm>
#include <vector>

#include "sluice/error.h"

namespace sluice::runtime {
namespace {

PipelineOptions pipeline_options(const io::ParticleQuery& query, uint64_t memory_cap, uint32_t max_frames) {
  PipelineOptions o;
  o.layers = query.layers;
  if (query.lod_level < 1) o.demand = ViewDemand::uniform(query.lod_level);
  std::vector<uint32_t> attributes;
  for (const size_t a : query.attributes) attributes.push_back(uint32_t(a));
  o.decode.attributes = attributes;
  o.decode.mode = DecodeMode::World;
  o.window.budget.memory_cap = memory_cap;
  o.window.budget.max_frames = max_frames;
  return o;
}

}  // namespace

ParticleStream::ParticleStream(std::shared_ptr<const io::ContainerReader> reader, StreamRange range, io::ParticleQuery query,
                               uint64_t memory_cap, uint32_t max_frames)
    : reader_(std::move(reader)), range_(range), query_(std::move(query)) {
  if (range_.step == 0) throw io::Error({reader_->path()}, "a step of 0 frames");
  range_.stop = std::min(range_.stop, reader_->frame_count());
  count_ = range_.start < range_.stop ? (range_.stop - range_.start + range_.step - 1) / range_.step : 0;
  if (count_ == 0) return;
  if (range_.loop) count_ = UINT64_MAX;
  pipeline_ = std::make_unique<Pipeline>(*reader_, allocator_, pipeline_options(query_, memory_cap, max_frames));
  PlaybackSchedule schedule;
  schedule.frame_count = range_.stop;
  schedule.start = int64_t(range_.start);
  schedule.stride = range_.step;
  schedule.end = range_.loop ? EndMode::Loop : EndMode::Stop;
  pipeline_->restart(schedule);
}

ParticleStream::~ParticleStream() = default;

uint64_t ParticleStream::remaining() const { return count_ - taken_; }

uint32_t ParticleStream::window_frames() const { return pipeline_ ? pipeline_->window() : 0; }

PipelineStats ParticleStream::stats() const { return pipeline_ ? pipeline_->stats() : PipelineStats{}; }

uint32_t ParticleStream::most_lent() const {
  // The pipeline reads ahead while the consumer holds fewer than three
  // quarters of its window (Pipeline::wait_next): half of that.
  const uint32_t window = window_frames();
  return std::max<uint32_t>(1, (window - window / 4) / 2);
}

std::optional<LentFrame> ParticleStream::next_lent() {
  if (taken_ == count_) return std::nullopt;
  const NextEntry entry = pipeline_->wait_next();
  if (entry.end) return std::nullopt;
  FrameHandle handle = pipeline_->take();
  ++taken_;
  if (handle.failed()) {
    const FrameError& e = *handle.error();
    throw io::Error(e.where, e.message);
  }
  // Thinned in place, and the caller may change the lent arrays: never
  // served again from this buffer (a loop reads the frame again).
  handle.spoil();
  const io::FrameHeader& header = handle.header();
  LentFrame out;
  out.index = handle.frame();
  out.time = header.time;
  out.arrays = io::world_spans(handle.buffers().particles, header.particle_count, query_.attributes.size());
  if (query_.lod_level < 1) out.arrays.count = io::thin(out.arrays, query_.lod_level, header.blob_voxel);
  out.handle = std::move(handle);
  return out;
}

std::optional<StreamedFrame> ParticleStream::next(io::ParticleArrays reuse) {
  std::optional<LentFrame> lent = next_lent();
  if (!lent) return std::nullopt;
  const io::ParticleSpans& from = lent->arrays;
  const uint64_t n = from.count;
  StreamedFrame out{lent->index, std::move(reuse)};
  io::ParticleArrays& a = out.arrays;
  a.time = lent->time;
  a.bytes_read = 0;
  a.positions.assign(from.positions, from.positions + 3 * n);
  a.lod.assign(from.lod, from.lod + n);
  a.layer.assign(from.layer, from.layer + n);
  a.attributes.resize(from.attributes.size());
  for (size_t k = 0; k < from.attributes.size(); ++k) a.attributes[k].assign(from.attributes[k], from.attributes[k] + n);
  return out;
}

}  // namespace sluice::runtime
