// `sluice export`: frames of a .sluice file back out as .vtp (+ .pvd), .csv
// or .ply for ParaView, Blender and friends; optionally thinned by LOD value.
#include <cstdio>
#include <stdexcept>

#include "commands.h"
#include "frame_range.h"
#include "human.h"
#include "progress.h"
#include "sluice/io/export.h"
#include "sluice/io/reader.h"

namespace sluice::app {
namespace {

struct ExportCommand {
  std::string input;
  std::string out;
  std::string frames;  // "A:B" inclusive, "A", "A:", ":B"; empty: all
  float lod_level = 1;
  std::vector<std::string> attributes;  // empty: every attribute of the file
  bool quiet = false, force = false;
};

void run_export(const ExportCommand& o) {
  const io::ContainerReader reader(o.input);
  io::SeriesOptions options;
  options.out = o.out;
  options.frames = parse_frame_list(o.frames, reader.frame_count());
  options.lod_level = o.lod_level;
  options.attributes = o.attributes;
  options.force = o.force;
  const bool thin = o.lod_level < 1;
  if (thin && !o.quiet && reader.header().lod_source == io::LodSource::ParticleOrder) {
    std::fprintf(stderr,
                 "warning: %s has LOD values from the particle order (no id array): --lod-level keeps the same\n"
                 "         particles every frame only if the solver wrote them in the same order every frame\n",
                 o.input.c_str());
  }
  const uint64_t count = options.frames.size();
  ProgressBar bar("frames", count, o.quiet);
  io::SeriesSummary total;
  try {
    total = io::export_series(reader, options, [&](const io::SeriesProgress& p) { bar.update(p.frames_done, p.bytes_in, p.bytes_out); });
  } catch (const io::OutputsExist& e) {
    throw std::runtime_error(std::string(e.what()) + "; pass --force to overwrite, or -o to choose another name");
  }
  bar.finish();

  const io::SeriesPlan& plan = total.plan;
  const std::string& first_file = plan.files.begin()->second;
  std::string where = first_file;
  if (count > 1) where += " .. " + plan.files.rbegin()->second;
  if (!plan.pvd.empty()) where += ", " + plan.pvd;
  const uint64_t files = count + (plan.pvd.empty() ? 0 : 1);
  std::string particles = human_count(double(total.kept)) + " particles";
  if (thin) {
    char level[32];
    std::snprintf(level, sizeof level, "%g", double(o.lod_level));
    particles = human_count(double(total.kept)) + " of " + human_count(double(total.particles)) + " particles (" +
                fixed(total.particles ? 100.0 * double(total.kept) / double(total.particles) : 0.0, 1) +
                "%, --lod-level " + level + ")";
  }
  if (o.quiet) return;
  std::printf("wrote %llu file%s (%s): %llu frame%s, %s, %s in %s\n", (unsigned long long)files, files == 1 ? "" : "s",
              where.c_str(), (unsigned long long)count, count == 1 ? "" : "s", particles.c_str(),
              human_bytes(double(total.bytes_out)).c_str(), human_duration(bar.elapsed()).c_str());
}

}  // namespace

void add_export(CLI::App& app) {
  auto o = std::make_shared<ExportCommand>();
  CLI::App* cmd = app.add_subcommand("export", "Write frames of a .sluice file as .vtp (ParaView), .csv or .ply");
  cmd->footer(
      "The format comes from OUT's extension. One frame goes to OUT itself; for several, out.vtp becomes\n"
      "out_00002.vtp, out_00003.vtp ... (the frame numbers of the file) and, for .vtp, a collection\n"
      "out.pvd with each frame's time that ParaView opens as a time series. OUT may also be a printf\n"
      "pattern (frames/shot_%04d.vtp; the collection is then frames/shot.pvd).\n\n"
      "Every file holds x, y, z (world units, float32), the stable 16-bit LOD value `lod` and the\n"
      "attributes (float32, as dequantized from the file). .vtp also stores the time (TimeValue).\n\n"
      "--lod-level L keeps the fraction L of the particles: those whose stable LOD value u = (lod+0.5)/65536\n"
      "passes the renderer's cLOD rule at importance 1, -ln(1-u) >= -ln(L) (i.e. u >= 1-L). LOD values are\n"
      "hashes of the particle ids, so the kept particles are spread uniformly and are the same in every frame.\n\n"
      "Examples:\n"
      "  sluice export dam.sluice -o dam/dam.vtp                      # every frame + dam/dam.pvd\n"
      "  sluice export dam.sluice -o f12.ply --frames 12              # one frame for Blender\n"
      "  sluice export big.sluice -o thin.csv --frames 0 --lod-level 0.1 --attribute rho\n"
      "  sluice export dam.sluice -o 'out/step_%04d.vtp' --frames 100: --force\n");
  cmd->add_option("input", o->input, ".sluice file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "Output .vtp, .csv or .ply (a series pattern for several frames)")->required();
  cmd->add_option("--frames", o->frames, "Frames A:B (inclusive), A, A: or :B, or a list of them: 0,25,50 (default: all)");
  cmd->add_option("--lod-level", o->lod_level,
                  "Keep this fraction of the particles, chosen by stable LOD value: the same ones every frame")
      ->capture_default_str()
      ->check(CLI::Range(0.0f, 1.0f));
  cmd->add_option("-a,--attribute", o->attributes, "Attributes to write (repeat, or a,b; default: all)")->delimiter(',');
  cmd->add_flag("-f,--force", o->force, "Overwrite outputs that exist");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bar or notes");
  cmd->callback([o] { run_export(*o); });
}

}  // namespace sluice::app
