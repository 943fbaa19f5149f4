// convert(): the decisions a conversion makes (header, times, up axis) and
// what it tells its observer; the frames themselves go through
// convert_frames (frames.cpp).
#include "sluice/import/convert.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "sluice/import/freed_memory.h"
#include "sluice/io/outliers.h"
#include "sluice/io/output_lock.h"
#include "sluice/io/spacing.h"
#include "sluice/io/up_axis.h"
#include "sluice/io/writer.h"

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, headers, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

void tell(const ConvertObserver& observer, Notice about, std::optional<uint64_t> frame, std::string text) {
  if (observer.noted) observer.noted(Note{about, frame, std::move(text)});
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

std::vector<std::string> carried_attributes(const ConvertOptions& o, const FrameSource& source) {
  if (!o.all_attributes) return o.attributes;
  std::vector<std::string> out;
  for (const std::string& a : source.info().arrays) {
    if (a != source.info().id_array && out.size() < kMaxAttributes) out.push_back(a);
  }
  return out;
}

// The input as the conversion reads it: its source, frame `from` (the first
// that reads) and the frames skipped before it.
struct Opened {
  std::unique_ptr<FrameSource> source;
  SourceOptions options;
  std::optional<ParticleFrame> first;
  uint64_t from = 0;
  std::vector<SkippedFrame> skipped;
};

// The first frame that reads: frame 0, or with skip_bad the first good one.
void read_first(const ConvertOptions& o, Opened& in) {
  for (uint64_t f = 0;; ++f) {
    try {
      in.first = in.source->read(f);
      in.from = f;
      return;
    } catch (const Error& e) {
      if (!o.skip_bad) throw;
      in.skipped.push_back({f, in.source->frame_name(f), e.what()});
      if (f + 1 == in.source->frame_count()) {
        throw Error({o.input}, "no frame could be read (" + std::to_string(in.skipped.size()) +
                                   " skipped); the last error: " + e.what());
      }
    }
  }
}

Opened open_input(const ConvertOptions& o) {
  Opened in;
  in.options.id_array = o.id_array;
  in.options.no_ids = o.no_ids;
  in.options.attributes = o.attributes;
  in.source = open_isolated(o.input, in.options, o.isolation);
  if (o.all_attributes) {  // the arrays are known once the source is open: open it again with them
    in.options.attributes = carried_attributes(o, *in.source);
    if (!in.options.attributes.empty()) in.source = open_isolated(o.input, in.options, o.isolation);
  }
  if (in.source->frame_count() == 0) throw Error({o.input}, "no frames to convert");
  read_first(o, in);
  return in;
}

// The first of frames `from`, `from` + 1, ... (at most 16) with particles
// enough to show a spacing (an empty or one-particle first frame, or one
// gathered at a point, shows none), and that spacing; the first frame and 0
// when none does. `held` keeps a frame read here.
std::pair<const ParticleFrame*, float> populated_frame(const ConvertOptions& o, const Opened& in,
                                                       std::optional<ParticleFrame>& held,
                                                       const ConvertObserver& observer) {
  if (const float s = estimate_spacing(in.first->positions); s > 0) return {&*in.first, s};
  const uint64_t last = std::min<uint64_t>(in.source->frame_count(), in.from + 16);
  for (uint64_t f = in.from + 1; f < last; ++f) {
    try {
      held = in.source->read(f);
      if (const float s = estimate_spacing(held->positions); s > 0) {
        tell(observer, Notice::SpacingLater, f,
             "frame " + std::to_string(in.from) + " shows no particle spacing (too few distinct particles); frame " +
                 std::to_string(f) + "'s is used");
        return {&*held, s};
      }
    } catch (const Error&) {
      // a bad frame: the conversion reports it in its turn
    }
  }
  if (o.spacing <= 0) {
    tell(observer, Notice::NoSpacing, std::nullopt,
         "none of the first frames has particles enough to show the spacing: the file states none (no narrow "
         "band, no position bound, radius from the extent)");
  }
  return {&*in.first, 0.0f};
}

// A radius never 0: spacing / 2, else a thousandth of the first frame's
// extent, else 1.
float radius_for(const ConvertOptions& o, float spacing, const ParticleFrame& first) {
  if (o.radius > 0) return o.radius;
  if (spacing > 0) return spacing * 0.5f;
  Aabb box;
  for (size_t i = 0; i + 2 < first.positions.size(); i += 3) box.extend(first.positions[i], first.positions[i + 1], first.positions[i + 2]);
  float extent = 0;
  for (int a = 0; a < 3 && !box.empty(); ++a) extent = std::max(extent, box.max[size_t(a)] - box.min[size_t(a)]);
  return extent > 0 ? extent * 1e-3f : 1.0f;
}

// Ids that repeat give repeated LOD values (export --lod-level 0.9 kept 0 of
// 52,780 particles whose ids were all equal): more than 1% repeats and the
// ids are not used.
bool ids_repeat(const ParticleFrame& frame) {
  if (frame.ids.size() < 2) return false;
  std::vector<uint64_t> ids = frame.ids;
  std::sort(ids.begin(), ids.end());
  const size_t distinct = size_t(std::unique(ids.begin(), ids.end()) - ids.begin());
  return double(ids.size() - distinct) > 0.01 * double(ids.size());
}

// The header from the options and the first frame with particles (times
// and the up axis are decided after).
FileHeader header_for(const ConvertOptions& o, const FrameSource& source, const ParticleFrame& populated,
                      float found_spacing, const std::vector<std::string>& attributes) {
  FileHeader header;
  header.position_coding = o.lossless ? PositionCoding::Float32 : PositionCoding::Quantized16;
  header.particle_spacing = o.spacing > 0 ? o.spacing : found_spacing;
  header.particle_radius = radius_for(o, header.particle_spacing, populated);
  header.precision_bits = o.lossless ? 0 : precision_bits_for(o.precision);
  if (o.drop_outliers > 0 && !(header.particle_spacing > 0)) {
    throw Error({o.input}, "dropping outliers counts in particle spacings, and the spacing is unknown: give the spacing");
  }
  for (const std::string& a : attributes) header.attributes.push_back({a});
  header.lod_id_array = source.info().id_array;
  header.lod_source = header.lod_id_array.empty() ? LodSource::ParticleOrder : LodSource::IdHash;
  header.source = source.info().description;
  return header;
}

// Times: the input's own, or a step given, or frame numbers (noted).
double choose_times(const ConvertOptions& o, const ParticleFrame& first, FileHeader& h, const ConvertObserver& observer) {
  h.frame_rate = float(o.fps > 0 ? o.fps : kDefaultFrameRate);
  if (first.time_given) {
    h.time_source = TimeSource::Input;
    if (o.dt > 0) tell(observer, Notice::TimesGiven, std::nullopt, "the input states its own times; dt is not used");
    return 0;
  }
  if (o.dt > 0 || o.fps > 0) {
    h.time_source = TimeSource::Step;
    return o.dt > 0 ? o.dt : 1.0 / o.fps;
  }
  h.time_source = TimeSource::FrameNumber;
  tell(observer, Notice::NoTimes, std::nullopt,
       "the input states no simulation times: frames are numbered and play at " +
           std::to_string(int(kDefaultFrameRate)) + "/s");
  return 0;
}

// Motion over the first frames, then pressure at the end, then the shape at
// the end, then +z (see io/up_axis.h).
UpFinding find_up(const ConvertOptions& o, const Opened& in, const std::vector<FrameShape>& first_frames,
                  const FrameShape& last, float spacing) {
  if (auto f = up_from_motion(first_frames, spacing)) return *f;
  const std::string pressure = pick_pressure_array(in.source->info().arrays);
  if (!pressure.empty()) {
    SourceOptions options;
    options.attributes = {pressure};
    options.id_array = o.id_array;
    options.no_ids = true;
    const auto again = open_isolated(o.input, options, o.isolation);
    const ParticleFrame frame = again->read(again->frame_count() - 1);
    if (auto f = up_from_pressure(frame.positions, frame.attributes.at(0), pressure)) return *f;
  }
  if (auto f = up_from_shape(last)) return *f;
  UpFinding f;
  f.reason = "nothing in the data shows it (no fall over the first frames, no pressure or density array that "
             "grows with depth, no flat layer): assumed";
  return f;
}

// e.g. "5 particles lie more than 100 spacings outside the rest (the
// farthest: particle 812, at (1e+06, 0.2, 0.3)); kept in chunks of their own".
std::string far_text(const FarReport& far, float spacing) {
  const std::string distance =
      spacing > 0 ? number(far.threshold / spacing) + " spacings" : number(far.threshold) + " (world units)";
  return std::to_string(far.count) + (far.count == 1 ? " particle lies" : " particles lie") + " more than " +
         distance + " outside the rest (the farthest: particle " + std::to_string(far.farthest) + ", at (" +
         number(far.position[0]) + ", " + number(far.position[1]) + ", " + number(far.position[2]) + ")); " +
         (far.dropped ? "dropped" : "kept in chunks of their own, left out of the framing");
}

// What the frames tell as they are written: notes, progress, the shapes
// that decide the up axis, and the header's up axis once the first frames
// show a fall (so a file cut short, and recovered, keeps it).
class FrameTally {
 public:
  FrameTally(const ConvertOptions& o, const Opened& in, FileHeader& header, ContainerWriter& writer,
             const FramesSettings& settings, const ConvertObserver& observer)
      : o_(o), in_(in), header_(header), writer_(writer), settings_(settings), observer_(observer) {}

  void operator()(const FrameConverted& p) {
    const uint64_t frames = in_.source->frame_count();
    for (const std::string& r : p.repairs) tell(observer_, Notice::Repair, p.frame, in_.source->frame_name(p.frame) + ": " + r);
    if (p.far.count > 0) {
      far_particles += p.far.count;
      ++far_frames;
      tell(observer_, Notice::FarParticles, p.frame,
           in_.source->frame_name(p.frame) + ": " + far_text(p.far, header_.particle_spacing));
    }
    if (p.shape && p.frame < settings_.shape_frames) first_frames.push_back(*p.shape);
    if (!o_.up && !early_up_ && first_frames.size() == std::min<uint64_t>(settings_.shape_frames, frames - in_.from)) {
      early_up_ = true;
      if (const auto up = up_from_motion(first_frames, header_.particle_spacing); up && up->up != header_.up) {
        header_.up = up->up;
        header_.up_evidence = up->evidence;
        writer_.update_header(header_);
      }
    }
    if (p.shape && p.frame + 1 == frames) last_shape = *p.shape;
    if (header_.time_source == TimeSource::Input && !p.time_given) ++untimed;
    input_bytes_ += p.input_bytes;
    if (observer_.progressed) observer_.progressed({p.frame + 1, frames, input_bytes_, writer_.bytes_written()});
  }

  uint64_t far_particles = 0, far_frames = 0, untimed = 0;
  std::vector<FrameShape> first_frames;
  FrameShape last_shape;

 private:
  const ConvertOptions& o_;
  const Opened& in_;
  FileHeader& header_;
  ContainerWriter& writer_;
  const FramesSettings& settings_;
  const ConvertObserver& observer_;
  bool early_up_ = false;
  uint64_t input_bytes_ = 0;
};

FramesSettings frames_settings(const ConvertOptions& o, const FileHeader& header, const ParticleFrame& populated) {
  FramesSettings s;
  // (a frame with particles; without far particles: one at 1e6 would make
  // every column one cell)
  s.shape_grid.box = find_far_particles(populated.positions, header.particle_spacing).bulk;
  s.shape_grid.cell = 2 * header.particle_spacing;
  s.shape_frames = o.up ? 0 : 16;
  s.drop_far = o.drop_outliers * header.particle_spacing;
  s.encode.chunk_particles = o.chunk;
  s.encode.zstd_level = o.level;
  s.encode.planes = o.planes;
  s.encode.lod_tiers = o.lod_tiers;
  s.encode.layers = o.layers;
  s.encode.band_voxel = o.band_voxel;
  s.encode.band_f2 = o.band_f2;
  s.skip_bad = o.skip_bad;
  s.max_in_flight = size_t(o.jobs > 0 ? o.jobs : tbb::info::default_concurrency()) + 1;
  return s;
}

// Until the frames have shown which way is up, the header says what the
// first frame's shape says (what a recovered, cut-off file keeps).
void provisional_up(const ConvertOptions& o, const FrameShape& first_shape, FileHeader& header) {
  const std::optional<UpFinding> found = up_from_shape(first_shape);
  header.up = o.up ? *o.up : found ? found->up : UpAxis::PosZ;
  header.up_evidence = o.up ? UpEvidence::Given : found ? found->evidence : UpEvidence::Default;
}

// The notes counted over the frames, once at the end.
void tell_totals(const ConvertOptions& o, const FrameTally& tally, const std::vector<SkippedFrame>& skipped,
                 const ConvertObserver& observer) {
  for (const SkippedFrame& s : skipped) tell(observer, Notice::Skipped, s.frame, s.error);
  if (tally.far_particles > 0) {
    tell(observer, Notice::FarTotal, std::nullopt,
         std::to_string(tally.far_particles) + " far particle" + (tally.far_particles == 1 ? "" : "s") + " in " +
             std::to_string(tally.far_frames) + " frame" + (tally.far_frames == 1 ? "" : "s") +
             (o.drop_outliers > 0 ? " dropped" : " kept (every other particle keeps its precision)"));
  }
  if (tally.untimed) {
    tell(observer, Notice::UntimedFrames, std::nullopt,
         std::to_string(tally.untimed) + " frames state no time while the others do: their time is their frame number");
  }
}

// The up axis once every frame is written: given, or found (see find_up).
void settle_up(const ConvertOptions& o, const Opened& in, const FrameTally& tally, const FrameShape& first_shape,
               FileHeader& header, ContainerWriter& writer, const ConvertObserver& observer) {
  if (o.up) {
    tell(observer, Notice::UpGiven, std::nullopt, "up: " + up_axis_name(header.up) + " (given)");
    return;
  }
  const FrameShape& last = in.source->frame_count() == 1 ? first_shape : tally.last_shape;
  const UpFinding up = find_up(o, in, tally.first_frames, last, header.particle_spacing);
  header.up = up.up;
  header.up_evidence = up.evidence;
  writer.update_header(header);
  tell(observer, Notice::Up, std::nullopt, "up: " + up_axis_name(up.up) + " (" + up_evidence_name(up.evidence) + "): " + up.reason);
}

}  // namespace

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

  // Frame 0 is read up front: the header needs its spacing, and it is kept
  // for the pipeline rather than read twice.
  Opened in = open_input(o);
  std::optional<ParticleFrame> held;
  const auto [populated, found_spacing] = populated_frame(o, in, held, observer);
  if (ids_repeat(*populated)) {
    tell(observer, Notice::RepeatedIds, std::nullopt,
         "the id array '" + in.source->info().id_array + "' repeats ids: LOD values follow the particle order instead");
    in.options.no_ids = true;
    in.source = open_isolated(o.input, in.options, o.isolation);
    in.first->ids.clear();
  }
  FileHeader header = header_for(o, *in.source, *populated, found_spacing, in.options.attributes);
  FramesSettings settings = frames_settings(o, header, *populated);
  settings.time_step = choose_times(o, *in.first, header, observer);
  const FrameShape first_shape = measure_shape(populated->positions);  // extent only (sampled)
  provisional_up(o, first_shape, header);
  if (observer.planned) observer.planned({in.source->info(), in.source->frame_count(), header, o.spacing > 0});
  if (header.lod_id_array.empty() && !in.options.no_ids) {
    tell(observer, Notice::NoIds, std::nullopt,
         "no particle id array found (looked for id, Idp, gid, particle_id, ...): LOD values follow the particle "
         "order, stable only if the solver writes particles in the same order each frame");
  }

  const OutputLock lock(output);
  const std::string partial = output + ".partial";
  ContainerWriter writer(partial, header);
  FrameTally tally(o, in, header, writer, settings, observer);
  FramesResult result;
  try {
    result = convert_frames(*in.source, std::move(in.first), writer, settings, std::ref(tally), in.from);
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
  settle_up(o, in, tally, first_shape, header, writer, observer);
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
