// `sluice convert`: simulation output -> .sluice, parallel over frames with
// a bounded number of frames in memory.
#include <tbb/global_control.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "commands.h"
#include "conversion.h"
#include "format_option.h"
#include "human.h"
#if SLUICE_WITH_MPI
#include "conversion_mpi.h"
#endif
#include "progress.h"
#include "sluice/io/maintenance.h"
#include "sluice/io/up_axis.h"

namespace sluice::app {
namespace {

struct ConvertCommand {
  import::ConvertOptions conversion;
  ConversionReport report;
  std::string output;
  std::string up;  // as typed
  bool smallest = false, gpu_decodable = false, in_process = false;
  int read_timeout = 120;
  bool force = false;
  bool mpi = false;  // over the ranks of an MPI job
};

// The flags that are not fields of import::ConvertOptions as they are typed.
import::ConvertOptions options_from(const ConvertCommand& c) {
  import::ConvertOptions o = c.conversion;
  if (!c.up.empty()) {
    o.up = io::parse_up_axis(c.up);
    if (!o.up) throw std::runtime_error("--up: expected x, y, z, -x, -y or -z, got '" + c.up + "'");
  }
  o.planes = c.gpu_decodable ? io::PlaneCoding::GpuDecodable : c.smallest ? io::PlaneCoding::Zstd : io::PlaneCoding::Packed;
  o.isolation = import_isolation(c.in_process, c.read_timeout);
  return o;
}

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

// Flags about reading simulation output: a .sluice input has settled them.
constexpr const char* kSolverOnly[] = {"--attribute", "--id-array", "--no-ids", "--lossless", "--spacing",
                                       "--radius", "--precision", "--drop-outliers", "--fps", "--dt", "--up",
                                       "--no-tiers", "--no-layers", "--band-voxel", "--band-f2", "--skip-bad",
                                       "--read-timeout", "--in-process", "--mpi"};

// A .sluice input rewritten in the layout --format names (io/maintenance.h).
void run_relayout(const ConvertCommand& c, const CLI::App& cmd) {
  for (const char* flag : kSolverOnly) {
    if (cmd.count(flag) > 0) {
      throw std::runtime_error(std::string(flag) + " applies to simulation output; " + c.conversion.input +
                               " is a .sluice file, rewritten as it is (its spacing, precision, layers and "
                               "attributes kept): leave " + flag + " out, or convert the solver's files again");
    }
  }
  const uint16_t major = c.conversion.format_major;
  const std::string version = major == 1 ? "1.5" : std::to_string(major) + ".0";
  const std::string output = !c.output.empty() ? c.output
                             : std::filesystem::path(c.conversion.input).stem().string() + "-" + version + ".sluice";
  if (std::filesystem::exists(output) && !c.force) {
    throw std::runtime_error(output + " exists; pass --force to overwrite it, or -o to choose another name");
  }
  io::RelayoutOptions r;
  r.format_major = major;
  if (c.gpu_decodable) r.planes = io::PlaneCoding::GpuDecodable;
  if (c.smallest) r.planes = io::PlaneCoding::Zstd;
  r.chunk_particles = c.conversion.chunk;
  r.zstd_level = c.conversion.level;
  std::optional<tbb::global_control> limit;
  if (c.conversion.jobs > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(c.conversion.jobs));
  const uint64_t frames = io::ContainerReader(c.conversion.input).frame_count();
  ProgressBar bar("frames", frames, c.report.quiet);
  const io::RelayoutReport s = io::relayout_container(c.conversion.input, output, r,
                                                      [&bar](uint64_t done, uint64_t) { bar.update(done); });
  bar.finish();
  std::printf("wrote %s: %llu frame%s, %s particle%s in the format %s layout, %s in -> %s out (%sx) in %s\n",
              output.c_str(), (unsigned long long)s.frames, s.frames == 1 ? "" : "s",
              human_count(double(s.particles)).c_str(), s.particles == 1 ? "" : "s", version.c_str(),
              human_bytes(double(s.input_bytes)).c_str(), human_bytes(double(s.output_bytes)).c_str(),
              fixed(double(s.output_bytes) / std::max(double(s.input_bytes), 1.0), 3).c_str(),
              human_duration(bar.elapsed()).c_str());
}

void run_convert(const ConvertCommand& c) {
  const import::ConvertOptions o = options_from(c);
  const std::string output = c.output.empty() ? default_output(o.input) : c.output;
  const auto refuse_existing = [&] {
    if (std::filesystem::exists(output) && !c.force) {
      throw std::runtime_error(output + " exists; pass --force to overwrite it, or -o to choose another name");
    }
  };
#if SLUICE_WITH_MPI
  if (!c.mpi) refuse_existing();  // (under MPI, rank 0 alone checks: one message, not one per rank)
  const std::optional<import::ConvertSummary> converted =
      c.mpi ? convert_mpi_and_report(o, output, c.report, refuse_existing) : convert_and_report(o, output, c.report);
  if (!converted) return;  // a rank but 0: rank 0 reports
  const import::ConvertSummary& s = *converted;
#else
  refuse_existing();
  if (c.mpi) {
    throw std::runtime_error("--mpi: this sluice was built without MPI; build it where libopenmpi-dev is installed "
                             "(CMake option SLUICE_MPI), or convert without --mpi");
  }
  const import::ConvertSummary s = convert_and_report(o, output, c.report);
#endif
  const double out = double(std::filesystem::file_size(output));
  const double per = s.particles ? out / double(s.particles) : 0;
  std::printf("wrote %s: %llu frame%s, %s particle%s, %s in -> %s out in %s (%s frames/s)\n", output.c_str(),
              (unsigned long long)s.frames, s.frames == 1 ? "" : "s", human_count(double(s.particles)).c_str(),
              s.particles == 1 ? "" : "s",
              human_bytes(double(s.input_bytes)).c_str(), human_bytes(out).c_str(), human_duration(s.elapsed.count()).c_str(),
              fixed(double(s.frames) / std::max(s.elapsed.count(), 1e-9), 1).c_str());
  if (s.particles == 0) return;
  // Tiny inputs cost more than 12 bytes a particle (header, index, tables).
  const bool smaller = per <= 12.0;
  std::printf("  %s bytes/particle with the LOD value%s: %sx %s than raw float32 xyz (12 bytes)\n", fixed(per, 2).c_str(),
              s.header.attributes.empty() ? "" : " and attributes", fixed(smaller ? 12.0 / per : per / 12.0, 2).c_str(),
              smaller ? "smaller" : "larger");
}

// `sluice convert --help`'s text after the options.
constexpr const char* kConvertFooter =
      "INPUT is a file, a quoted glob ('out/fluid_*.vtu', naturally sorted: 2 before 10), a .pvd series or a\n"
      "directory. Formats: .vtu .vtp .pvtu .pvtp .vtk (legacy) .pvd .csv .xyz.\n\n"
      "Each particle gets a 16-bit LOD value hashed from its id array (id, Idp, gid, ... are found\n"
      "automatically), so level of detail drops the same particles every frame.\n\n"
      "Times come from the input (.pvd, TimeValue fields); without them give --dt or --fps. Which way is up\n"
      "is found from the frames (the fluid falls along -up; else pressure grows downward; else a flat layer)\n"
      "and stored in the file; --up overrides it.\n\n"
      "Each frame is split into the particles near the free surface (the narrow band, found on a voxel\n"
      "grid), the interior, and voxel blobs that stand in for the interior's thickness. Players read the\n"
      "surface and blobs by default (less to read, decode and draw for the same picture); --layers all\n"
      "in play and render reads every particle. --no-layers writes frames unclassified.\n\n"
      "Examples:\n"
      "  sluice convert 'dam/dam_break_3d_fluid_*.vtu' -o dam.sluice --attribute rho\n"
      "  sluice convert run.pvd --lossless --jobs 8\n\n"
      "Damaged input: every count in a file is checked against its bytes before anything is read. VTK's XML\n"
      "readers run in worker processes, so a crash or hang on a damaged file is an error naming that file.\n"
      "A bad frame stops the conversion (the output keeps the frames before it) unless --skip-bad.\n\n"
      "A .sluice INPUT is rewritten in the layout --format names (default 2.0, frames ordered coarse to\n"
      "fine): `sluice convert old.sluice -o new.sluice`. Its header, layers and attributes are kept; positions\n"
      "are quantized again in the new cells, each within the file's stated bound of the input's.\n";

}  // namespace

void add_convert(CLI::App& app) {
  auto c = std::make_shared<ConvertCommand>();
  import::ConvertOptions* o = &c->conversion;
  CLI::App* cmd = app.add_subcommand("convert", "Convert simulation output (VTK, CSV, XYZ) into a .sluice file");
  cmd->footer(kConvertFooter);
  cmd->add_option("input", o->input, "File, quoted glob, .pvd or directory")->required();
  cmd->add_option("-o,--output", c->output, "Output file (default: named after the input)");
  cmd->add_option("-a,--attribute", o->attributes, "Point-data array to keep for colouring (repeat, or a,b)")
      ->delimiter(',');
  cmd->add_option("--id-array", o->id_array, "Particle id array for stable LOD values (default: auto-detect)");
  cmd->add_flag("--no-ids", o->no_ids, "Ignore id arrays: LOD values follow particle order");
  cmd->add_flag("--lossless", o->lossless, "Store float32 positions instead of 16-bit quantized ones");
  cmd->add_option("--spacing", o->spacing, "Particle rest spacing in world units (default: estimated)");
  cmd->add_option("--radius", o->radius, "Render radius in world units (default: spacing / 2)");
  cmd->add_option("--precision", o->precision,
                  "Largest position error as a fraction of the spacing, rounded down to a power of two\n"
                  "(default 1/1024 = 0.00098); stated in the file, kept for every particle whatever lies\n"
                  "far away (chunks are kept narrow enough)")
      ->check(CLI::Range(1e-12, 0.5));
  cmd->add_option("--drop-outliers", o->drop_outliers,
                  "Leave out particles more than DIST spacings outside the rest of their frame (escaped or\n"
                  "corrupt ones), listed. Without it they are kept in chunks of their own and warned about")
      ->type_name("DIST")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--fps", o->fps,
                  "Playback frames per second (default 30); for an input without times also the time step 1/N");
  cmd->add_option("--dt", o->dt, "Seconds of simulation between frames, for an input without times");
  cmd->add_option("--up", c->up,
                  "World axis that points up: x, y, z, -x, -y or -z (default: found from the data: how the fluid "
                  "falls, its pressure, its shape)");
  cmd->add_option("--chunk", o->chunk, "Most particles per chunk (octree cells)")->capture_default_str()
      ->check(CLI::Range(1u, 1u << 20));
  cmd->add_option("--level", o->level, "zstd level, 1 (fast) to 19 (small)")->capture_default_str()
      ->check(CLI::Range(1, 19));
  cmd->add_flag("--smallest", c->smallest,
                "zstd on every plane it shrinks most: files 1-3% smaller, decoding up to 1.4x slower "
                "(default: small-valued planes are bit-packed)");
  cmd->add_flag("--gpu-decodable", c->gpu_decodable,
                "No zstd planes (each stored or bit-packed): every chunk decodes on the GPU with no CPU work but\n"
                "its checksum (`sluice play` decodes on the GPU by default); files some percent larger");
  add_format_option(*cmd, o->format_major);
  cmd->add_flag("--no-tiers", [o](int64_t) { o->lod_tiers = false; },
                "One record per chunk instead of one per LOD tier: a few percent smaller, but a player then reads\n"
                "every particle of a chunk it draws, however far away (docs/format.md, \"LOD tiers\")");
  cmd->add_flag("--no-layers", [o](int64_t) { o->layers = false; },
                "Do not classify the narrow band: every frame is one layer of all its particles");
  cmd->add_option("--band-voxel", o->band_voxel,
                  "Voxel side of the narrow band and of the interior's blobs, world units (default: twice the "
                  "spacing)")
      ->check(CLI::PositiveNumber);
  cmd->add_option_function<std::string>(
         "--band-f2", [o](const std::string& f2) { o->band_f2 = f2 == "asymmetry" ? io::F2Test::Asymmetry : io::F2Test::All; },
         "Which particles of a selected second-layer voxel are surface: 'every' (the dissertation's choice,\n"
         "the default) or 'asymmetry' (only those whose neighbours lie to one side: fewer bytes read;\n"
         "docs/narrow_band.md compares them)")
      ->check(CLI::IsMember({"every", "asymmetry"}));
  cmd->add_option("-j,--jobs", o->jobs, "Worker threads (default: all cores)");
  cmd->add_flag("--skip-bad", o->skip_bad,
                "Leave out frames that cannot be read (damaged, cut short) and list them; without it the\n"
                "conversion stops at the first one, and the output keeps the frames before it");
  cmd->add_option("--read-timeout", c->read_timeout,
                  "Seconds VTK's reader may take for one frame before the frame counts as bad")
      ->capture_default_str()
      ->check(CLI::Range(1, 86400));
  cmd->add_flag("--in-process", c->in_process,
                "Read VTK XML files in this process rather than in worker processes (a reader crash on a\n"
                "damaged file then ends sluice; see docs/import.md)");
  cmd->add_flag("-f,--force", c->force, "Overwrite the output if it exists");
  cmd->add_flag("--mpi", c->mpi,
                "Convert over the ranks of an MPI job into the one output (MPI-IO), byte for byte what one\n"
                "process writes: `mpirun -np 16 sluice convert --mpi --jobs 1 'run/*.vtu' -o run.sluice`\n"
                "(srun the same way). --jobs is threads per rank (default: the node's cores shared among its\n"
                "ranks). The input must be the same path on every node. docs/convert_mpi.md");
  cmd->add_flag("-q,--quiet", c->report.quiet, "No progress bar or notes");
  cmd->callback([c, cmd] {
    if (io::is_container(c->conversion.input)) {
      run_relayout(*c, *cmd);
    } else {
      run_convert(*c);
    }
  });
}

}  // namespace sluice::app
