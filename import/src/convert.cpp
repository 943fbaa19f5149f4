// convert(): one process converts every frame into one file. The decisions
// and what they tell the observer are convert_steps.cpp's; the frames go
// through convert_frames (frames.cpp).
#include "sluice/import/convert.h"
#include "sluice/import/frames.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <optional>

#include "convert_steps.h"
#include "frame_work.h"
#include "read_ahead.h"
#include "sluice/import/freed_memory.h"
#include "sluice/io/writer.h"

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, headers, shapes
using io::Error;  // (not sluice::Error, its base)

ConvertStopped::ConvertStopped(const io::Error& cause, std::string output, uint64_t frames_kept, bool output_complete)
    : io::Error(cause.where(), cause.message()),
      output_(std::move(output)),
      frames_kept_(frames_kept),
      output_complete_(output_complete) {}

ConvertSummary convert(const ConvertOptions& o, const std::string& output, const ConvertObserver& observer) {
  const auto start = std::chrono::steady_clock::now();
  const KeepFreedMemory keep;  // VTK and the importer allocate per frame (freed_memory.h)
  std::optional<tbb::global_control> limit;
  if (o.jobs > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.jobs));

  // Frames 1 ... jobs are read while frame 0 decides the header.
  ReadAhead ahead(o, 1, uint64_t(o.jobs > 0 ? o.jobs : tbb::info::default_concurrency()));
  Prepared prepared = prepare_conversion(o, observer);
  Opened& in = prepared.in;
  std::map<uint64_t, ParticleFrame> read = std::move(ahead.take(in.options).frames);
  read.erase(read.begin(), read.upper_bound(in.from));  // skipped, or frame `from`, read by the decisions
  read.emplace(in.from, std::move(*in.first));
  FileHeader& header = prepared.header;
  const FramesSettings& settings = prepared.settings;

  const OutputLock lock(output);
  const std::string partial = output + ".partial";
  ContainerWriter writer(partial, header);
  const HeaderChanged rewrite = [&writer](const FileHeader& h) { writer.update_header(h); };
  FrameTally tally(o, in, header, settings, observer, rewrite, [&writer] { return writer.bytes_written(); });
  FramesResult result;
  try {
    result = convert_frames_from(*in.source, std::move(read), writer, settings, std::ref(tally), in.from);
  } catch (const Error& e) {
    if (writer.failed()) throw ConvertStopped(e, partial, writer.frames_written(), false);
    tell_totals(o, tally, in.skipped, observer);
    const uint64_t kept = writer.frames_written();
    writer.finish();
    std::filesystem::rename(partial, output);
    throw ConvertStopped(e, output, kept, true);
  }
  in.skipped.insert(in.skipped.end(), result.skipped.begin(), result.skipped.end());
  tell_totals(o, tally, in.skipped, observer);
  settle_up(o, in, tally, prepared.first_shape, header, rewrite, observer);
  writer.finish();
  std::filesystem::rename(partial, output);

  ConvertSummary s;
  s.frames = result.frames;
  s.skipped = std::move(in.skipped);
  s.particles = result.particles;
  s.far_particles = tally.far_particles;
  s.far_frames = tally.far_frames;
  s.input_bytes = result.input_bytes;
  s.elapsed = std::chrono::steady_clock::now() - start;
  s.header = header;
  return s;
}

}  // namespace sluice::import
