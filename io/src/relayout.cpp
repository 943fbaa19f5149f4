// relayout_container(): a .sluice file decoded frame by frame and encoded
// again in another layout (maintenance.h).
#include "sluice/io/maintenance.h"

#include <tbb/parallel_pipeline.h>

#include <atomic>
#include <exception>
#include <numeric>

#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/writer.h"
#include "sluice/io/particles.h"
#include "sluice/io/reader.h"

namespace sluice::io {
namespace {

// Whether every chunk of frame `frame` (its `record`, parsed as `header`)
// decodes on the GPU (no zstd plane).
bool decodes_on_gpu(const ContainerReader& input, uint64_t frame, std::span<const std::byte> record,
                    const FrameHeader& header) {
  if (!gpu_decodable(input.header())) return false;
  GpuDecodePlan plan;
  plan_gpu_frame(header, input.header(), {}, plan, input.location(frame));
  for (size_t c = 0; c < header.chunks.size(); ++c) {
    const ChunkDesc& chunk = header.chunks[c];
    const auto payload = record.subspan(chunk.offset, chunk.compressed_size);
    if (!plan_gpu_chunk(payload, header, input.header(), {}, c, plan, input.location(frame, c))) return false;
  }
  return true;
}

// Frame `f` read whole (surface and interior) and encoded for `header`.
EncodedFrame relaid(const ContainerReader& input, uint64_t f, const FileHeader& header, const EncodeOptions& encode) {
  ParticleQuery query;
  query.attributes.resize(input.header().attributes.size());
  std::iota(query.attributes.begin(), query.attributes.end(), size_t{0});
  const ParticleArrays p = read_particles(input, f, query);
  FrameInput in;
  in.positions = p.positions;
  in.lod = p.lod;
  for (const auto& a : p.attributes) in.attributes.emplace_back(a);
  in.time = p.time;
  return encode_frame(in, header, encode);
}

}  // namespace

EncodeOptions encoding_of(const ContainerReader& input, const RelayoutOptions& options) {
  EncodeOptions e;
  e.chunk_particles = options.chunk_particles;
  e.zstd_level = options.zstd_level;
  e.layers = false;
  e.lod_tiers = false;
  if (input.frame_count() == 0) return e;
  // Frame 0 read once: its table for the layers and tiers, its planes for
  // the coding.
  const std::vector<std::byte> record = input.read_record(0);
  const FrameHeader first = input.parse_record(0, record);
  for (const ChunkDesc& c : first.chunks) {
    e.layers |= c.layer != Layer::All;
    e.lod_tiers |= c.tier > 0 || c.last_tier > 0;
  }
  // Unset (0) gives the encoder's default of twice the spacing.
  e.band_voxel = first.blob_voxel;
  e.planes = options.planes ? *options.planes
             : decodes_on_gpu(input, 0, record, first) ? PlaneCoding::GpuDecodable
                                        : PlaneCoding::Packed;
  return e;
}

RelayoutReport relayout_container(const std::filesystem::path& input, const std::filesystem::path& output,
                                  const RelayoutOptions& options, const ProgressFn& progress) {
  std::error_code same_error;
  if (std::filesystem::exists(output) && std::filesystem::equivalent(input, output, same_error)) {
    throw Error({output.string()}, "is the input: write the new layout to another file (-o)");
  }
  const ContainerReader reader(input);
  FileHeader header = reader.header();
  set_format_version(header, options.format_major);
  RelayoutReport report;
  report.encode = encoding_of(reader, options);

  const OutputLock lock(output);
  const std::filesystem::path partial = output.string() + ".partial";
  try {
    ContainerWriter writer(partial, header);
    const uint64_t frames = reader.frame_count();
    uint64_t next = 0;
    // Errors travel as values to the in-order stage: thrown from a stage,
    // one would cancel the frames being encoded mid-way (TBB cancels their
    // nested parallel loops, which then return unfinished).
    struct Relaid {
      EncodedFrame frame;
      std::exception_ptr error;
    };
    std::atomic<bool> stop{false};
    std::exception_ptr failed;
    // Each frame's decode and encode is itself parallel over cells: two
    // frames in flight (one worked on while the one before is written)
    // keep the workers busy and bound the memory to two frames' worth
    // (`sluice convert` of a 10M x 4 file: 1.49 GB at most in memory).
    tbb::parallel_pipeline(
        2,
        tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                         [&](tbb::flow_control& fc) -> uint64_t {
                                           if (next == frames || stop.load()) fc.stop();
                                           return next++;
                                         }) &
            tbb::make_filter<uint64_t, Relaid>(tbb::filter_mode::parallel,
                                               [&](uint64_t f) {
                                                 Relaid r;
                                                 try {
                                                   r.frame = relaid(reader, f, header, report.encode);
                                                 } catch (...) {
                                                   r.error = std::current_exception();
                                                 }
                                                 return r;
                                               }) &
            tbb::make_filter<Relaid, void>(tbb::filter_mode::serial_in_order, [&](Relaid r) {
              if (failed) return;
              try {
                if (r.error) std::rethrow_exception(r.error);
                report.particles += count_in(r.frame.header, LayerSet::particles());
                writer.append(std::move(r.frame));
                ++report.frames;
                if (progress) progress(report.frames, frames);
              } catch (...) {
                failed = std::current_exception();
                stop = true;
              }
            }));
    if (failed) std::rethrow_exception(failed);
    writer.finish();
    std::filesystem::rename(partial, output);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw;
  }
  report.input_bytes = reader.file_size();
  report.output_bytes = std::filesystem::file_size(output);
  return report;
}

}  // namespace sluice::io
