#include "frame_stream.h"

#include <vector>

#include "sluice/io/error.h"
#include "sluice/runtime/error.h"

namespace sluice::python {
namespace {

runtime::PipelineOptions pipeline_options(const io::ParticleQuery& query, uint64_t memory_cap) {
  runtime::PipelineOptions o;
  o.layers = query.layers;
  if (query.lod_level < 1) o.demand = runtime::ViewDemand::uniform(query.lod_level);
  std::vector<uint32_t> attributes;
  for (const size_t a : query.attributes) attributes.push_back(uint32_t(a));
  o.decode.attributes = attributes;
  o.window.budget.memory_cap = memory_cap;
  return o;
}

}  // namespace

FrameStream::FrameStream(std::shared_ptr<const io::ContainerReader> reader, StreamRange range, io::ParticleQuery query,
                         uint64_t memory_cap)
    : reader_(std::move(reader)), range_(range), query_(std::move(query)) {
  if (range_.step == 0) throw io::Error({reader_->path()}, "a step of 0 frames");
  range_.stop = std::min(range_.stop, reader_->frame_count());
  count_ = range_.start < range_.stop ? (range_.stop - range_.start + range_.step - 1) / range_.step : 0;
  if (count_ == 0) return;
  pipeline_ = std::make_unique<runtime::Pipeline>(*reader_, allocator_, pipeline_options(query_, memory_cap));
  runtime::PlaybackSchedule schedule;
  schedule.frame_count = range_.stop;
  schedule.start = int64_t(range_.start);
  schedule.stride = range_.step;
  schedule.end = runtime::EndMode::Stop;
  pipeline_->restart(schedule);
}

FrameStream::~FrameStream() = default;

uint64_t FrameStream::remaining() const { return count_ - taken_; }

uint32_t FrameStream::window_frames() const { return pipeline_ ? pipeline_->window() : 0; }

std::optional<StreamedFrame> FrameStream::next() {
  if (taken_ == count_) return std::nullopt;
  const runtime::NextEntry entry = pipeline_->wait_next();
  if (entry.end) return std::nullopt;
  runtime::FrameHandle handle = pipeline_->take();
  ++taken_;
  if (handle.failed()) {
    const runtime::FrameError& e = *handle.error();
    throw io::Error(e.where, e.message);
  }
  const runtime::FrameBuffers& b = handle.buffers();
  std::vector<std::span<const uint16_t>> streams;
  for (size_t k = 0; k < query_.attributes.size(); ++k) {
    streams.emplace_back(b.attributes[k].data(), handle.header().particle_count);
  }
  StreamedFrame out{handle.frame(), io::particles_of(handle.header(), handle.chunk_first(), b.particles, streams,
                                                     reader_->header(), query_)};
  out.arrays.bytes_read = 0;  // the pipeline's reads are in its stats, not per frame
  return out;
}

}  // namespace sluice::python
