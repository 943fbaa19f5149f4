// The conversion behind `sluice convert` and the play/render cache.
#include "conversion.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>

#include "isolated_source.h"
#include "progress.h"
#include "sluice/io/convert.h"
#include "sluice/io/freed_memory.h"
#include "sluice/io/import.h"
#include "sluice/io/outliers.h"
#include "sluice/io/output_lock.h"
#include "sluice/io/spacing.h"
#include "sluice/io/up_axis.h"
#include "sluice/io/writer.h"

namespace sluice::app {
namespace {

void note(const ConversionOptions& o, const std::string& line) {
  if (!o.quiet) std::fprintf(stderr, "%s\n", line.c_str());
}

std::vector<std::string> carried_attributes(const ConversionOptions& o, const io::FrameSource& source) {
  if (!o.all_attributes) return o.attributes;
  std::vector<std::string> out;
  for (const std::string& a : source.info().arrays) {
    if (a != source.info().id_array && out.size() < io::kMaxAttributes) out.push_back(a);
  }
  return out;
}

// The input, read in worker processes when a third-party reader reads it.
std::unique_ptr<io::FrameSource> open_input(const ConversionOptions& o, const io::ImportOptions& import) {
  std::unique_ptr<io::FrameSource> source = io::open_source(o.input, import);
  if (o.in_process || !source->info().third_party_reader) return source;
  return isolate(std::move(source), o.input, import, std::chrono::seconds(o.read_timeout));
}

// The first frame that reads: frame 0, or with skip_bad the first good one.
uint64_t read_first(const ConversionOptions& o, const io::FrameSource& source, std::optional<io::ParticleFrame>& first,
                    std::vector<io::SkippedFrame>& skipped) {
  for (uint64_t f = 0;; ++f) {
    try {
      first = source.read(f);
      return f;
    } catch (const io::Error& e) {
      if (!o.skip_bad) throw;
      skipped.push_back({f, source.frame_name(f), e.what()});
      if (f + 1 == source.frame_count()) {
        throw std::runtime_error(o.input + ": no frame could be read (" + std::to_string(skipped.size()) +
                                 " skipped); the last error: " + e.what());
      }
    }
  }
}

void report_skipped(const std::vector<io::SkippedFrame>& skipped) {
  if (skipped.empty()) return;
  std::fprintf(stderr, "skipped %zu frame%s that could not be read:\n", skipped.size(), skipped.size() == 1 ? "" : "s");
  for (const auto& s : skipped) std::fprintf(stderr, "  %s\n", s.error.c_str());
}

// Times: the input's own, or a step the user gave, or frame numbers (said so).
void choose_times(const ConversionOptions& o, const io::ParticleFrame& first, io::FileHeader& h, double& step) {
  h.frame_rate = float(o.fps > 0 ? o.fps : kDefaultFrameRate);
  step = 0;
  if (first.time_given) {
    h.time_source = io::TimeSource::Input;
    if (o.dt > 0) note(o, "note: the input states its own times; --dt is not used");
    return;
  }
  if (o.dt > 0 || o.fps > 0) {
    step = o.dt > 0 ? o.dt : 1.0 / o.fps;
    h.time_source = io::TimeSource::Step;
    return;
  }
  h.time_source = io::TimeSource::FrameNumber;
  note(o, "note: the input states no simulation times: frames are numbered and play at " +
              std::to_string(int(kDefaultFrameRate)) +
              "/s. Pass --dt SECONDS (time between frames) or --fps N to give them times.");
}

// Motion over the first frames, then pressure at the end, then the shape at
// the end, then +z (see io/up_axis.h).
io::UpFinding find_up(const ConversionOptions& o, const std::vector<io::FrameShape>& first_frames,
                      const io::FrameShape& last, const io::FrameSource& source, float spacing) {
  if (auto f = io::up_from_motion(first_frames, spacing)) return *f;
  const std::string pressure = io::pick_pressure_array(source.info().arrays);
  if (!pressure.empty()) {
    io::ImportOptions import;
    import.attributes = {pressure};
    import.id_array = o.id_array;
    import.no_ids = true;
    const auto again = open_input(o, import);
    const io::ParticleFrame frame = again->read(again->frame_count() - 1);
    if (auto f = io::up_from_pressure(frame.positions, frame.attributes.at(0), pressure)) return *f;
  }
  if (auto f = io::up_from_shape(last)) return *f;
  io::UpFinding f;
  f.reason = "nothing in the data shows it (no fall over the first frames, no pressure or density array that "
             "grows with depth, no flat layer): assumed";
  return f;
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

// One line per frame with far particles (outliers.h), e.g. "frame 12: 5
// particles lie more than 100 spacings outside the rest (the farthest:
// particle 812, at (1e+06, 0.2, 0.3)); kept in chunks of their own ...".
std::string far_warning(const std::string& frame, const io::FarReport& far, float spacing) {
  const std::string distance =
      spacing > 0 ? number(far.threshold / spacing) + " spacings" : number(far.threshold) + " (world units)";
  std::string line = frame + ": " + std::to_string(far.count) + (far.count == 1 ? " particle lies" : " particles lie") +
                     " more than " + distance + " outside the rest (the farthest: particle " +
                     std::to_string(far.farthest) + ", at (" + number(far.position[0]) + ", " +
                     number(far.position[1]) + ", " + number(far.position[2]) + "))";
  if (far.dropped) return line + "; dropped (--drop-outliers)";
  return line + "; kept in chunks of their own, left out of the framing" +
         (spacing > 0 ? "; --drop-outliers " + number(far.threshold / spacing) + " removes them" : "");
}

// The first of frames `from`, `from` + 1, ... (at most 16) with particles
// enough to show a spacing (an empty or one-particle first frame, or one
// gathered at a point, shows none), and that spacing; the first frame and 0
// when none does. `held` keeps a frame read here.
std::pair<const io::ParticleFrame*, float> populated_frame(const ConversionOptions& o, const io::FrameSource& source,
                                                           const io::ParticleFrame& first, uint64_t from,
                                                           std::optional<io::ParticleFrame>& held) {
  if (const float s = io::estimate_spacing(first.positions); s > 0) return {&first, s};
  const uint64_t last = std::min<uint64_t>(source.frame_count(), from + 16);
  for (uint64_t f = from + 1; f < last; ++f) {
    try {
      held = source.read(f);
      if (const float s = io::estimate_spacing(held->positions); s > 0) {
        note(o, "note: frame " + std::to_string(from) + " shows no particle spacing (too few distinct particles); " +
                    "frame " + std::to_string(f) + "'s is used");
        return {&*held, s};
      }
    } catch (const io::Error&) {
      // a bad frame: the conversion reports it in its turn
    }
  }
  if (o.spacing <= 0) {
    note(o, "warning: none of the first frames has particles enough to show the spacing: the file states none\n"
            "         (no narrow band, no position bound, radius from the extent). Pass --spacing to give it.");
  }
  return {&first, 0.0f};
}

// A radius never 0: spacing / 2, else a thousandth of the first frame's
// extent, else 1.
float radius_for(const ConversionOptions& o, float spacing, const io::ParticleFrame& first) {
  if (o.radius > 0) return o.radius;
  if (spacing > 0) return spacing * 0.5f;
  io::Aabb box;
  for (size_t i = 0; i + 2 < first.positions.size(); i += 3) box.extend(first.positions[i], first.positions[i + 1], first.positions[i + 2]);
  float extent = 0;
  for (int a = 0; a < 3 && !box.empty(); ++a) extent = std::max(extent, box.max[size_t(a)] - box.min[size_t(a)]);
  return extent > 0 ? extent * 1e-3f : 1.0f;
}

// Ids that repeat give repeated LOD values (export --lod-level 0.9 kept 0 of
// 52,780 particles whose ids were all equal): more than 1% repeats and the
// ids are not used.
bool ids_repeat(const io::ParticleFrame& frame) {
  if (frame.ids.size() < 2) return false;
  std::vector<uint64_t> ids = frame.ids;
  std::sort(ids.begin(), ids.end());
  const size_t distinct = size_t(std::unique(ids.begin(), ids.end()) - ids.begin());
  return double(ids.size() - distinct) > 0.01 * double(ids.size());
}

std::optional<io::UpAxis> up_given(const ConversionOptions& o) {
  if (o.up.empty()) return std::nullopt;
  const std::optional<io::UpAxis> up = io::parse_up_axis(o.up);
  if (!up) throw std::runtime_error("--up: expected x, y, z, -x, -y or -z, got '" + o.up + "'");
  return up;
}

// The header from the options and the first frame with particles (times
// and the up axis are decided after).
io::FileHeader header_for(const ConversionOptions& o, const io::FrameSource& source, const io::ParticleFrame& populated,
                          float found_spacing, const std::vector<std::string>& attributes) {
  io::FileHeader header;
  header.position_coding = o.lossless ? io::PositionCoding::Float32 : io::PositionCoding::Quantized16;
  header.particle_spacing = o.spacing > 0 ? o.spacing : found_spacing;
  header.particle_radius = radius_for(o, header.particle_spacing, populated);
  header.precision_bits = o.lossless ? 0 : io::precision_bits_for(o.precision);
  if (o.drop_outliers > 0 && !(header.particle_spacing > 0)) {
    throw std::runtime_error("--drop-outliers counts in particle spacings, and the spacing of " + o.input +
                             " is unknown: pass --spacing too");
  }
  for (const std::string& a : attributes) header.attributes.push_back({a});
  header.lod_id_array = source.info().id_array;
  header.lod_source = header.lod_id_array.empty() ? io::LodSource::ParticleOrder : io::LodSource::IdHash;
  header.source = source.info().description;
  return header;
}

// What is about to happen, on stderr (unless quiet).
void describe_plan(const ConversionOptions& o, const io::FrameSource& source, uint64_t frames, const io::FileHeader& header) {
  if (!o.quiet) {
    std::fprintf(stderr, "converting %s\n  %llu frames, spacing %g (%s), radius %g, %s positions, LOD from %s\n",
                 source.info().description.c_str(), (unsigned long long)frames, header.particle_spacing,
                 o.spacing > 0 ? "given" : "estimated", header.particle_radius,
                 o.lossless ? "float32 (lossless)" : "16-bit quantized",
                 header.lod_id_array.empty() ? "particle order" : ("id array '" + header.lod_id_array + "'").c_str());
  }
  if (header.lod_id_array.empty()) {
    note(o, "warning: no particle id array found (looked for id, Idp, gid, particle_id, ...): LOD values follow\n"
            "         the particle order, stable only if the solver writes particles in the same order each\n"
            "         frame. Pass --id-array NAME if the ids have another name.");
  }
}

// The warnings counted over the frames, once at the end.
void report_totals(const ConversionOptions& o, size_t suppressed, uint64_t far_particles, uint64_t far_frames,
                   uint64_t untimed) {
  if (suppressed) std::fprintf(stderr, "warning: %zu more warnings not shown\n", suppressed);
  if (far_particles > 0) {
    note(o, "warning: " + std::to_string(far_particles) + " far particle" + (far_particles == 1 ? "" : "s") + " in " +
                std::to_string(far_frames) + " frame" + (far_frames == 1 ? "" : "s") +
                (o.drop_outliers > 0 ? " dropped" : " kept (every other particle keeps its precision)"));
  }
  if (untimed) {
    note(o, "warning: " + std::to_string(untimed) + " frames state no time while the others do: their time is "
                "their frame number");
  }
}

}  // namespace

ConversionSummary convert_input(const ConversionOptions& o, const std::string& output) {
  const io::KeepFreedMemory keep;  // VTK and the importer allocate per frame (freed_memory.h)
  std::optional<tbb::global_control> limit;
  if (o.jobs > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.jobs));
  const int jobs = o.jobs > 0 ? o.jobs : tbb::info::default_concurrency();
  const std::optional<io::UpAxis> given_up = up_given(o);

  io::ImportOptions import;
  import.id_array = o.id_array;
  import.no_ids = o.no_ids;
  import.attributes = o.attributes;
  std::unique_ptr<io::FrameSource> source = open_input(o, import);
  if (o.all_attributes) {  // the arrays are known once the source is open: open it again with them
    import.attributes = carried_attributes(o, *source);
    if (!import.attributes.empty()) source = open_input(o, import);
  }
  const uint64_t frames = source->frame_count();
  if (frames == 0) throw std::runtime_error(o.input + ": no frames to convert");

  // Frame 0 is read up front: the header needs its spacing, and it is kept
  // for the pipeline rather than read twice.
  std::optional<io::ParticleFrame> first;
  std::vector<io::SkippedFrame> skipped;
  const uint64_t from = read_first(o, *source, first, skipped);
  std::optional<io::ParticleFrame> held;
  const auto [populated, found_spacing] = populated_frame(o, *source, *first, from, held);
  if (ids_repeat(*populated)) {
    note(o, "warning: the id array '" + source->info().id_array + "' repeats ids" +
                ": LOD values follow the particle order instead (pass --id-array NAME for another array)");
    import.no_ids = true;
    source = open_input(o, import);
    first->ids.clear();
  }
  io::FileHeader header = header_for(o, *source, *populated, found_spacing, import.attributes);
  io::ConvertSettings settings;
  choose_times(o, *first, header, settings.time_step);
  // Until the frames have shown which way is up, the header says what the
  // first frame's shape says (what a recovered, cut-off file keeps).
  // (a frame with particles; without far particles: one at 1e6 would make
  // every column one cell)
  settings.shape_grid.box = io::find_far_particles(populated->positions, header.particle_spacing).bulk;
  settings.shape_grid.cell = 2 * header.particle_spacing;
  // Extent only (sampled): the columns of frame 0 are measured in the pipeline.
  const io::FrameShape first_shape = io::measure_shape(populated->positions);
  const std::optional<io::UpFinding> provisional = io::up_from_shape(first_shape);
  header.up = given_up ? *given_up : provisional ? provisional->up : io::UpAxis::PosZ;
  header.up_evidence = given_up ? io::UpEvidence::Given : provisional ? provisional->evidence : io::UpEvidence::Default;
  settings.shape_frames = given_up ? 0 : 16;

  describe_plan(o, *source, frames, header);

  // One writer per output: a second convert (or player filling the same
  // cache entry) stops here, naming this one, instead of sharing the .partial.
  const io::OutputLock lock(output);
  const std::string partial = output + ".partial";
  io::ContainerWriter writer(partial, header);
  settings.drop_far = o.drop_outliers * header.particle_spacing;
  settings.encode.chunk_particles = o.chunk;
  settings.encode.zstd_level = o.level;
  settings.encode.planes = o.gpu_decodable ? io::PlaneCoding::GpuDecodable
                          : o.smallest      ? io::PlaneCoding::Zstd
                                            : io::PlaneCoding::Packed;
  settings.encode.lod_tiers = o.lod_tiers;
  settings.encode.layers = o.layers;
  settings.encode.band_voxel = o.band_voxel;
  settings.encode.band_f2 = o.band_f2;
  settings.max_in_flight = size_t(jobs) + 1;
  ProgressBar bar("frames", frames, o.quiet);
  size_t warnings = 0, suppressed = 0;
  uint64_t bytes_in = 0, untimed = 0, far_particles = 0, far_frames = 0;
  bool early_up = false;
  std::vector<io::FrameShape> first_frames;
  io::FrameShape last_shape;
  settings.skip_bad = o.skip_bad;
  const auto on_frame = [&](const io::ConvertProgress& p) {
    for (const std::string& r : p.repairs) {
      if (warnings++ < o.max_warnings) bar.warn(source->frame_name(p.frame) + ": " + r);
      else ++suppressed;
    }
    if (p.far.count > 0) {
      far_particles += p.far.count;
      ++far_frames;
      if (warnings++ < o.max_warnings) bar.warn(far_warning(source->frame_name(p.frame), p.far, header.particle_spacing));
      else ++suppressed;
    }
    if (p.shape && p.frame < settings.shape_frames) first_frames.push_back(*p.shape);
    // Once the first frames have shown a fall, the header says so: a file
    // cut short (and recovered) then keeps it.
    if (!given_up && !early_up && first_frames.size() == std::min<uint64_t>(settings.shape_frames, frames - from)) {
      early_up = true;
      if (const auto up = io::up_from_motion(first_frames, header.particle_spacing); up && up->up != header.up) {
        header.up = up->up;
        header.up_evidence = up->evidence;
        writer.update_header(header);
      }
    }
    if (p.shape && p.frame + 1 == frames) last_shape = *p.shape;
    if (header.time_source == io::TimeSource::Input && !p.time_given) ++untimed;
    bytes_in += p.input_bytes;
    bar.update(p.frame + 1, bytes_in, writer.bytes_written());
  };
  io::ConvertResult result;
  try {
    result = io::convert_frames(*source, std::move(first), writer, settings, on_frame, from);
  } catch (const io::Error& e) {
    bar.finish();
    if (writer.failed()) {  // writing failed (disk full?): nothing is renamed into place
      throw std::runtime_error(std::string(e.what()) + "\n  " + partial + " holds the " +
                               std::to_string(writer.frames_written()) +
                               " frames written before; `sluice recover` rebuilds a file of them once there is room");
    }
    // A bad frame: stop cleanly, the output keeps every frame before it.
    report_skipped(skipped);
    const uint64_t kept = writer.frames_written();
    writer.finish();
    std::filesystem::rename(partial, output);
    throw std::runtime_error(std::string(e.what()) + "\n  " + output + " holds the " + std::to_string(kept) +
                             " frame" + (kept == 1 ? "" : "s") +
                             " before it; pass --skip-bad to leave bad frames out and convert the rest");
  }
  skipped.insert(skipped.end(), result.skipped.begin(), result.skipped.end());
  bar.finish();
  report_skipped(skipped);
  report_totals(o, suppressed, far_particles, far_frames, untimed);

  if (given_up) {
    note(o, "up: " + io::up_axis_name(header.up) + " (given)");
  } else {
    if (frames == 1) last_shape = first_shape;
    const io::UpFinding up = find_up(o, first_frames, last_shape, *source, header.particle_spacing);
    header.up = up.up;
    header.up_evidence = up.evidence;
    writer.update_header(header);
    note(o, "up: " + io::up_axis_name(up.up) + " (" + io::up_evidence_name(up.evidence) + "): " + up.reason +
                ". Pass --up to choose.");
  }
  writer.finish();
  std::filesystem::rename(partial, output);

  ConversionSummary s;
  s.frames = result.frames;
  s.skipped = std::move(skipped);
  s.particles = result.particles;
  s.far_particles = far_particles;
  s.far_frames = far_frames;
  s.input_bytes = result.input_bytes;
  s.seconds = bar.elapsed();
  s.header = header;
  return s;
}

}  // namespace sluice::app
