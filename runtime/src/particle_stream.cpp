#include "sluice/runtime/particle_stream.h"

#include <vector>

#include "sluice/io/error.h"

namespace sluice::runtime {
namespace {

PipelineOptions pipeline_options(const io::ParticleQuery& query, uint64_t memory_cap, uint32_t max_frames) {
  PipelineOptions o;
  o.layers = query.layers;
  if (query.lod_level < 1) o.demand = ViewDemand::uniform(query.lod_level);
  std::vector<uint32_t> attributes;
  for (const size_t a : query.attributes) attributes.push_back(uint32_t(a));
  o.decode.attributes = attributes;
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

std::optional<StreamedFrame> ParticleStream::next(io::ParticleArrays reuse) {
  if (taken_ == count_) return std::nullopt;
  const NextEntry entry = pipeline_->wait_next();
  if (entry.end) return std::nullopt;
  FrameHandle handle = pipeline_->take();
  ++taken_;
  if (handle.failed()) {
    const FrameError& e = *handle.error();
    throw io::Error(e.where, e.message);
  }
  const FrameBuffers& b = handle.buffers();
  std::vector<std::span<const uint16_t>> streams;
  for (size_t k = 0; k < query_.attributes.size(); ++k) {
    streams.emplace_back(b.attributes[k].data(), handle.header().particle_count);
  }
  StreamedFrame out{handle.frame(), std::move(reuse)};
  io::particles_into(handle.header(), handle.chunk_first(), b.particles, streams, reader_->header(), query_, out.arrays);
  return out;
}

}  // namespace sluice::runtime
