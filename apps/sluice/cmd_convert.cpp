// `sluice convert`: simulation output -> .sluice, parallel over frames with
// a bounded number of frames in memory.
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <filesystem>
#include <optional>

#include "commands.h"
#include "human.h"
#include "progress.h"
#include "sluice/io/convert.h"
#include "sluice/io/import.h"
#include "sluice/io/spacing.h"

namespace sluice::app {
namespace {

struct ConvertOptions {
  std::string input;
  std::string output;
  std::vector<std::string> attributes;
  std::string id_array;
  bool no_ids = false;
  bool lossless = false;
  float spacing = 0, radius = 0, fps = 30;
  uint32_t chunk = 65536;
  int level = 3;
  bool smallest = false;
  int jobs = 0;
  bool force = false, quiet = false;
  size_t max_warnings = 20;
};

std::string default_output(const std::string& input) {
  std::filesystem::path p(input);
  if (p.has_filename() && p.filename().string().find_first_of("*?[") == std::string::npos) {
    return p.stem().string() + ".sluice";
  }
  // A glob or directory: name it after the directory.
  const auto dir = p.has_filename() ? p.parent_path() : p.parent_path().parent_path();
  const std::string name = dir.filename().string();
  return (name.empty() || name == "." ? "out" : name) + ".sluice";
}

void run_convert(const ConvertOptions& o) {
  const std::string output = o.output.empty() ? default_output(o.input) : o.output;
  if (std::filesystem::exists(output) && !o.force) {
    throw std::runtime_error(output + " exists; pass --force to overwrite it, or -o to choose another name");
  }
  std::optional<tbb::global_control> limit;
  if (o.jobs > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.jobs));
  const int jobs = o.jobs > 0 ? o.jobs : tbb::info::default_concurrency();

  io::ImportOptions import;
  import.attributes = o.attributes;
  import.id_array = o.id_array;
  import.no_ids = o.no_ids;
  const auto source = io::open_source(o.input, import);
  const uint64_t frames = source->frame_count();
  if (frames == 0) throw std::runtime_error(o.input + ": no frames to convert");

  // Frame 0 is read up front: the header needs its spacing, and it is kept
  // for the pipeline rather than read twice.
  std::optional<io::ParticleFrame> first = source->read(0);
  io::FileHeader header;
  header.position_coding = o.lossless ? io::PositionCoding::Float32 : io::PositionCoding::Quantized16;
  header.particle_spacing = o.spacing > 0 ? o.spacing : io::estimate_spacing(first->positions);
  header.particle_radius = o.radius > 0 ? o.radius : header.particle_spacing * 0.5f;
  header.frame_rate = o.fps;
  for (const std::string& a : o.attributes) header.attributes.push_back({a});
  header.lod_id_array = source->info().id_array;
  header.lod_source = header.lod_id_array.empty() ? io::LodSource::ParticleOrder : io::LodSource::IdHash;
  header.source = source->info().description;

  if (!o.quiet) {
    std::fprintf(stderr, "converting %s\n  %llu frames, spacing %g (%s), radius %g, %s positions, LOD from %s\n",
                 source->info().description.c_str(), (unsigned long long)frames, header.particle_spacing,
                 o.spacing > 0 ? "given" : "estimated", header.particle_radius,
                 o.lossless ? "float32 (lossless)" : "16-bit quantized",
                 header.lod_id_array.empty() ? "particle order" : ("id array '" + header.lod_id_array + "'").c_str());
  }
  if (header.lod_id_array.empty() && !o.quiet) {
    std::fprintf(stderr,
                 "warning: no particle id array found (looked for id, Idp, gid, particle_id, ...): LOD values follow\n"
                 "         the particle order, stable only if the solver writes particles in the same order each\n"
                 "         frame. Pass --id-array NAME if the ids have another name.\n");
  }

  const std::string partial = output + ".partial";
  io::ContainerWriter writer(partial, header);
  io::EncodeOptions encode;
  encode.chunk_particles = o.chunk;
  encode.zstd_level = o.level;
  encode.pack_planes = !o.smallest;
  ProgressBar bar("frames", frames, o.quiet);
  size_t warnings = 0, suppressed = 0;
  uint64_t bytes_in = 0;
  const io::ConvertResult result = io::convert_frames(
      *source, std::move(first), writer, encode, size_t(jobs) + 1, [&](const io::ConvertProgress& p) {
        for (const std::string& r : p.repairs) {
          if (warnings++ < o.max_warnings) bar.warn(source->frame_name(p.frame) + ": " + r);
          else ++suppressed;
        }
        bytes_in += p.input_bytes;
        bar.update(p.frame + 1, bytes_in, writer.bytes_written());
      });
  const uint64_t particles = result.particles;
  writer.finish();
  bar.finish();
  std::filesystem::rename(partial, output);
  if (suppressed) std::fprintf(stderr, "warning: %zu more repairs not shown\n", suppressed);

  const double out = double(std::filesystem::file_size(output));
  const double per = particles ? out / double(particles) : 0;
  std::printf("wrote %s: %llu frames, %s particles, %s in -> %s out in %s (%s frames/s)\n", output.c_str(),
              (unsigned long long)frames, human_count(double(particles)).c_str(), human_bytes(double(result.input_bytes)).c_str(),
              human_bytes(out).c_str(), human_duration(bar.elapsed()).c_str(),
              fixed(double(frames) / bar.elapsed(), 1).c_str());
  std::printf("  %s bytes/particle with the LOD value%s: %sx smaller than raw float32 xyz (12 bytes)\n",
              fixed(per, 2).c_str(), header.attributes.empty() ? "" : " and attributes", fixed(12.0 / per, 2).c_str());
}

}  // namespace

void add_convert(CLI::App& app) {
  auto o = std::make_shared<ConvertOptions>();
  CLI::App* cmd = app.add_subcommand("convert", "Convert simulation output (VTK, CSV, XYZ) into a .sluice file");
  cmd->footer(
      "INPUT is a file, a quoted glob ('out/fluid_*.vtu', naturally sorted: 2 before 10), a .pvd series or a\n"
      "directory. Formats: .vtu .vtp .pvtu .pvtp .vtk (legacy) .pvd .csv .xyz.\n\n"
      "Each particle gets a 16-bit LOD value hashed from its id array (id, Idp, gid, ... are found\n"
      "automatically), so level of detail drops the same particles every frame.\n\n"
      "Examples:\n"
      "  sluice convert 'dam/dam_break_3d_fluid_*.vtu' -o dam.sluice --attribute rho\n"
      "  sluice convert run.pvd --lossless --jobs 8\n");
  cmd->add_option("input", o->input, "File, quoted glob, .pvd or directory")->required();
  cmd->add_option("-o,--output", o->output, "Output file (default: named after the input)");
  cmd->add_option("-a,--attribute", o->attributes, "Point-data array to keep for colouring (repeat, or a,b)")
      ->delimiter(',');
  cmd->add_option("--id-array", o->id_array, "Particle id array for stable LOD values (default: auto-detect)");
  cmd->add_flag("--no-ids", o->no_ids, "Ignore id arrays: LOD values follow particle order");
  cmd->add_flag("--lossless", o->lossless, "Store float32 positions instead of 16-bit quantized ones");
  cmd->add_option("--spacing", o->spacing, "Particle rest spacing in world units (default: estimated)");
  cmd->add_option("--radius", o->radius, "Render radius in world units (default: spacing / 2)");
  cmd->add_option("--fps", o->fps, "Nominal playback frame rate")->capture_default_str();
  cmd->add_option("--chunk", o->chunk, "Most particles per chunk (octree cells)")->capture_default_str()
      ->check(CLI::Range(1u, 1u << 20));
  cmd->add_option("--level", o->level, "zstd level, 1 (fast) to 19 (small)")->capture_default_str()
      ->check(CLI::Range(1, 19));
  cmd->add_flag("--smallest", o->smallest,
                "zstd on every plane it shrinks most: files 1-3% smaller, decoding up to 1.4x slower "
                "(default: small-valued planes are bit-packed)");
  cmd->add_option("-j,--jobs", o->jobs, "Worker threads (default: all cores)");
  cmd->add_flag("-f,--force", o->force, "Overwrite the output if it exists");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bar or notes");
  cmd->callback([o] { run_convert(*o); });
}

}  // namespace sluice::app
