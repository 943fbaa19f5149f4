#include "sluice/io/convert.h"

#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <filesystem>

#include "sluice/io/lod.h"

namespace sluice::io {
namespace {

struct Work {
  uint64_t frame = 0;
  uint64_t input_bytes = 0;
  std::vector<std::string> repairs;
  EncodedFrame encoded;
};

uint64_t source_file_bytes(const FrameSource& source, uint64_t frame) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(source.frame_name(frame), ec);
  return ec ? 0 : size;
}

Work encode_one(const FrameSource& source, ParticleFrame frame, uint64_t index, const FileHeader& header,
                const EncodeOptions& options) {
  Work w;
  w.frame = index;
  w.input_bytes = source_file_bytes(source, index);
  w.repairs = std::move(frame.repairs);
  const std::vector<uint16_t> lod = lod_values(frame.ids, frame.count());
  FrameInput in;
  in.positions = frame.positions;
  in.lod = lod;
  for (const auto& a : frame.attributes) in.attributes.emplace_back(a);
  in.time = frame.time;
  try {
    w.encoded = encode_frame(in, header, options);
  } catch (const Error& e) {
    throw Error({source.frame_name(index), index}, e.message());
  }
  return w;
}

}  // namespace

ConvertResult convert_frames(const FrameSource& source, std::optional<ParticleFrame> first, ContainerWriter& writer,
                             const EncodeOptions& options, size_t max_in_flight,
                             const std::function<void(const ConvertProgress&)>& on_frame) {
  const uint64_t frames = source.frame_count();
  ConvertResult result;
  uint64_t next = 0;
  tbb::parallel_pipeline(
      std::max<size_t>(2, max_in_flight),
      tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> uint64_t {
                                         if (next == frames) fc.stop();
                                         return next++;
                                       }) &
          tbb::make_filter<uint64_t, Work>(tbb::filter_mode::parallel,
                                           [&](uint64_t f) {
                                             ParticleFrame frame = (f == 0 && first) ? std::move(*first) : source.read(f);
                                             return encode_one(source, std::move(frame), f, writer.header(), options);
                                           }) &
          tbb::make_filter<Work, void>(tbb::filter_mode::serial_in_order, [&](Work w) {
            result.frames++;
            result.particles += w.encoded.header.particle_count;
            result.raw_bytes += w.encoded.raw_bytes;
            result.input_bytes += w.input_bytes;
            writer.append(std::move(w.encoded));
            if (on_frame) on_frame({w.frame, w.input_bytes, w.repairs});
          }));
  return result;
}

}  // namespace sluice::io
