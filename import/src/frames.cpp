#include "sluice/import/frames.h"

#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <filesystem>
#include <map>

#include "sluice/io/lod.h"
#include "sluice/io/point_set.h"
#include "frame_work.h"

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

uint64_t source_file_bytes(const FrameSource& source, uint64_t frame) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(source.frame_name(frame), ec);
  return ec ? 0 : size;
}

// Removes frame's particles `gone` (ascending indices) from every array.
void remove_particles(ParticleFrame& frame, std::span<const uint32_t> gone) {
  const size_t n = frame.count();
  size_t next = 0, kept = 0;
  for (size_t i = 0; i < n; ++i) {
    if (next < gone.size() && gone[next] == i) {
      ++next;
      continue;
    }
    for (size_t a = 0; a < 3; ++a) frame.positions[3 * kept + a] = frame.positions[3 * i + a];
    if (!frame.ids.empty()) frame.ids[kept] = frame.ids[i];
    for (auto& values : frame.attributes) values[kept] = values[i];
    ++kept;
  }
  frame.positions.resize(3 * kept);
  if (!frame.ids.empty()) frame.ids.resize(kept);
  for (auto& values : frame.attributes) values.resize(kept);
}

FrameWork encode_one(const FrameSource& source, ParticleFrame frame, uint64_t index, const FileHeader& header,
                     const FramesSettings& settings) {
  FrameWork w;
  w.frame = index;
  w.time_given = frame.time_given;
  if (settings.drop_far > 0) {
    const FarParticles far = find_far_particles(frame.positions, header.particle_spacing, settings.drop_far);
    if (!far.far.empty()) {
      w.far = report_far(far, frame.positions, true);
      remove_particles(frame, far.far);
    }
  }
  const uint64_t last = source.frame_count() - 1;
  if (settings.shape_frames > 0 && (index < settings.shape_frames || index == last)) w.shape = measure_shape(frame.positions, &settings.shape_grid);
  if (!frame.time_given && settings.time_step > 0) frame.time = double(index) * settings.time_step;
  w.input_bytes = source_file_bytes(source, index);
  w.repairs = std::move(frame.repairs);
  const std::vector<uint16_t> lod = lod_values(frame.ids, frame.count());
  FrameInput in;
  in.positions = frame.positions;
  in.lod = lod;
  for (const auto& a : frame.attributes) in.attributes.emplace_back(a);
  in.time = frame.time;
  try {
    w.encoded = encode_frame(in, header, settings.encode);
    if (w.encoded.far.count > 0) w.far = w.encoded.far;
  } catch (const Error& e) {
    throw Error({source.frame_name(index), index}, e.message());
  }
  return w;
}

}  // namespace

FrameWork convert_frame(const FrameSource& source, std::optional<ParticleFrame> read, uint64_t f, const FileHeader& header,
                        const FramesSettings& settings) {
  try {
    ParticleFrame frame = read ? std::move(*read) : source.read(f);
    return encode_one(source, std::move(frame), f, header, settings);
  } catch (const Error& e) {
    FrameWork w;
    w.frame = f;
    w.error = e;
    return w;
  }
}

FramesResult convert_frames(const FrameSource& source, std::optional<ParticleFrame> first, ContainerWriter& writer,
                             const FramesSettings& settings,
                             const std::function<void(const FrameConverted&)>& on_frame, uint64_t from) {
  std::map<uint64_t, ParticleFrame> read;
  if (first) read.emplace(from, std::move(*first));
  return convert_frames_from(source, std::move(read), writer, settings, on_frame, from);
}

FramesResult convert_frames_from(const FrameSource& source, std::map<uint64_t, ParticleFrame> read,
                                 ContainerWriter& writer, const FramesSettings& settings,
                                 const std::function<void(const FrameConverted&)>& on_frame, uint64_t from) {
  const uint64_t frames = source.frame_count();
  FramesResult result;
  uint64_t next = from;
  // Errors travel as values to the in-order stage, so every frame before a
  // bad one is written before the conversion stops.
  std::atomic<bool> stop{false};
  std::optional<Error> stopped;
  // A failed write (disk full) or callback stops the pipeline the same way,
  // as a value: thrown, it would cancel the frames being encoded mid-way
  // (TBB cancels their nested parallel loops, which then return unfinished).
  std::exception_ptr failed;
  tbb::parallel_pipeline(
      std::max<size_t>(2, settings.max_in_flight),
      tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> uint64_t {
                                         if (next == frames || stop.load()) fc.stop();
                                         return next++;
                                       }) &
          tbb::make_filter<uint64_t, FrameWork>(tbb::filter_mode::parallel,
                                                [&](uint64_t f) {
                                                  // (entries are taken by one task each: no two touch one)
                                                  std::optional<ParticleFrame> frame;
                                                  if (const auto it = read.find(f); it != read.end()) {
                                                    frame = std::move(it->second);
                                                  }
                                                  return convert_frame(source, std::move(frame), f, writer.header(), settings);
                                                }) &
          tbb::make_filter<FrameWork, void>(tbb::filter_mode::serial_in_order, [&](FrameWork w) {
            if (stopped) return;
            if (w.error) {
              if (settings.skip_bad) {
                result.skipped.push_back({w.frame, source.frame_name(w.frame), w.error->what()});
                return;
              }
              stopped = std::move(w.error);
              stop = true;
              return;
            }
            if (failed) return;
            try {
              const uint64_t particles = count_in(w.encoded.header, LayerSet::particles());
              const uint64_t raw = w.encoded.raw_bytes;
              writer.append(std::move(w.encoded));
              result.frames++;
              result.particles += particles;
              result.raw_bytes += raw;
              result.input_bytes += w.input_bytes;
              if (on_frame) on_frame({w.frame, w.input_bytes, w.repairs, w.shape, w.time_given, w.far});
            } catch (...) {
              failed = std::current_exception();
              stop = true;
            }
          }));
  if (failed) std::rethrow_exception(failed);
  if (stopped) throw *stopped;
  return result;
}

}  // namespace sluice::import
