// The steps of a conversion that the serial converter (convert.cpp) and the
// MPI one (convert_mpi.cpp) share (see convert_steps.h).
#include "convert_steps.h"

#include <tbb/info.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "sluice/io/point_set.h"
#include "sluice/io/up_axis.h"

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
  in.source = open_source(o, in.options);
  read_first(o, in);
  return in;
}

// A spacing the file can state: its position bound (spacing / 2^bits) a
// normal float. A frame of a few particles at wildly different scales can
// estimate one of 1e-45, whose bound rounds to 0: a promise of exactness no
// 16-bit encoding keeps (found by fuzz_vtk_import).
bool stateable_spacing(const ConvertOptions& o, float spacing) {
  const int bits = o.lossless ? kDefaultPrecisionBits : precision_bits_for(o.precision);
  return spacing > 0 && std::isfinite(spacing) && std::ldexp(spacing, -bits) >= std::numeric_limits<float>::min();
}

// The first of frames `from`, `from` + 1, ... (at most 16) with particles
// enough to show a spacing (an empty or one-particle first frame, or one
// gathered at a point, shows none), and that spacing; the first frame and 0
// when none does. `held` keeps a frame read here.
std::pair<const ParticleFrame*, float> populated_frame(const ConvertOptions& o, const Opened& in,
                                                       std::optional<ParticleFrame>& held,
                                                       const ConvertObserver& observer) {
  if (const float s = estimate_spacing(in.first->positions); stateable_spacing(o, s)) return {&*in.first, s};
  const uint64_t last = std::min<uint64_t>(in.source->frame_count(), in.from + 16);
  for (uint64_t f = in.from + 1; f < last; ++f) {
    try {
      held = in.source->read(f);
      if (const float s = estimate_spacing(held->positions); stateable_spacing(o, s)) {
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
  tbb::parallel_sort(ids.begin(), ids.end());  // (10M ids: 0.55 s on one core)
  const size_t distinct = size_t(std::unique(ids.begin(), ids.end()) - ids.begin());
  return double(ids.size() - distinct) > 0.01 * double(ids.size());
}

// The header from the options and the first frame with particles (times
// and the up axis are decided after).
FileHeader header_for(const ConvertOptions& o, const FrameSource& source, const ParticleFrame& populated,
                      float found_spacing, const std::vector<std::string>& attributes) {
  FileHeader header;
  header.position_coding = o.lossless ? PositionCoding::Float32 : PositionCoding::Quantized16;
  if (o.spacing > 0 && !stateable_spacing(o, o.spacing)) {
    char given[32];
    std::snprintf(given, sizeof given, "%g", double(o.spacing));
    throw Error({o.input}, "--spacing " + std::string(given) +
                               " is too small for a float position bound at this precision: give the spacing in "
                               "larger units (scale the input) or a coarser --precision");
  }
  header.particle_spacing = o.spacing > 0 ? o.spacing : found_spacing;
  header.particle_radius = radius_for(o, header.particle_spacing, populated);
  header.precision_bits = o.lossless ? 0 : precision_bits_for(o.precision);
  set_format_version(header, o.format_major);
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



// Until the frames have shown which way is up, the header says what the
// first frame's shape says (what a recovered, cut-off file keeps).
void provisional_up(const ConvertOptions& o, const FrameShape& first_shape, FileHeader& header) {
  const std::optional<UpFinding> found = up_from_shape(first_shape);
  header.up = o.up ? *o.up : found ? found->up : UpAxis::PosZ;
  header.up_evidence = o.up ? UpEvidence::Given : found ? found->evidence : UpEvidence::Default;
}

}  // namespace

std::unique_ptr<FrameSource> open_source(const ConvertOptions& o, SourceOptions& options) {
  options.id_array = o.id_array;
  options.no_ids = o.no_ids;
  options.attributes = o.attributes;
  std::unique_ptr<FrameSource> source = open_isolated(o.input, options, o.isolation);
  if (o.all_attributes) {  // the arrays are known once the source is open: open it again with them
    options.attributes = carried_attributes(o, *source);
    if (!options.attributes.empty()) source = open_isolated(o.input, options, o.isolation);
  }
  if (source->frame_count() == 0) throw Error({o.input}, "no frames to convert");
  return source;
}

FramesSettings frames_settings(const ConvertOptions& o, const FileHeader& header, const Aabb& shape_box) {
  FramesSettings s;
  s.shape_grid.box = shape_box;
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

Prepared prepare_conversion(const ConvertOptions& o, const ConvertObserver& observer) {
  Prepared p;
  // Frame 0 is read up front: the header needs its spacing, and it is kept
  // for the frames rather than read twice.
  p.in = open_input(o);
  Opened& in = p.in;
  std::optional<ParticleFrame> held;
  const auto [populated, found_spacing] = populated_frame(o, in, held, observer);
  if (ids_repeat(*populated)) {
    tell(observer, Notice::RepeatedIds, std::nullopt,
         "the id array '" + in.source->info().id_array + "' repeats ids: LOD values follow the particle order instead");
    in.options.no_ids = true;
    in.source = open_isolated(o.input, in.options, o.isolation);
    in.first->ids.clear();
  }
  p.header = header_for(o, *in.source, *populated, found_spacing, in.options.attributes);
  // (a frame with particles; without far particles: one at 1e6 would make
  // every column one cell)
  p.settings = frames_settings(o, p.header, find_far_particles(populated->positions, p.header.particle_spacing).bulk);
  p.settings.time_step = choose_times(o, *in.first, p.header, observer);
  p.first_shape = measure_shape(populated->positions);  // extent only (sampled)
  provisional_up(o, p.first_shape, p.header);
  if (observer.planned) observer.planned({in.source->info(), in.source->frame_count(), p.header, o.spacing > 0});
  if (p.header.lod_id_array.empty() && !in.options.no_ids) {
    tell(observer, Notice::NoIds, std::nullopt,
         "no particle id array found (looked for id, Idp, gid, particle_id, ...): LOD values follow the particle "
         "order, stable only if the solver writes particles in the same order each frame");
  }
  return p;
}

FrameTally::FrameTally(const ConvertOptions& o, const Opened& in, FileHeader& header, const FramesSettings& settings,
                       const ConvertObserver& observer, HeaderChanged header_changed,
                       std::function<uint64_t()> bytes_written)
    : o_(o),
      in_(in),
      header_(header),
      settings_(settings),
      observer_(observer),
      header_changed_(std::move(header_changed)),
      bytes_written_(std::move(bytes_written)) {}

void FrameTally::operator()(const FrameConverted& p) {
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
      header_changed_(header_);
    }
  }
  if (p.shape && p.frame + 1 == frames) last_shape = *p.shape;
  if (header_.time_source == TimeSource::Input && !p.time_given) ++untimed;
  input_bytes_ += p.input_bytes;
  if (observer_.progressed) observer_.progressed({p.frame + 1, frames, input_bytes_, bytes_written_()});
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
               FileHeader& header, const HeaderChanged& header_changed, const ConvertObserver& observer) {
  if (o.up) {
    tell(observer, Notice::UpGiven, std::nullopt, "up: " + up_axis_name(header.up) + " (given)");
    return;
  }
  const FrameShape& last = in.source->frame_count() == 1 ? first_shape : tally.last_shape;
  const UpFinding up = find_up(o, in, tally.first_frames, last, header.particle_spacing);
  header.up = up.up;
  header.up_evidence = up.evidence;
  header_changed(header);
  tell(observer, Notice::Up, std::nullopt, "up: " + up_axis_name(up.up) + " (" + up_evidence_name(up.evidence) + "): " + up.reason);
}


}  // namespace sluice::import
