// `sluice export`: frames of a .sluice file back out as .vtp (+ .pvd), .csv
// or .ply for ParaView, Blender and friends; optionally thinned by LOD value.
#include <tbb/info.h>
#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "commands.h"
#include "frame_range.h"
#include "human.h"
#include "progress.h"
#include "sluice/io/export.h"
#include "sluice/io/reader.h"

namespace sluice::app {
namespace {

namespace fs = std::filesystem;

struct ExportCommand {
  std::string input;
  std::string out;
  std::string frames;  // "A:B" inclusive, "A", "A:", ":B"; empty: all
  float lod_level = 1;
  std::vector<std::string> attributes;  // empty: every attribute of the file
  bool quiet = false, force = false;
};

// A printf pattern with one integer conversion ("shot_%04d.vtp"), split so it
// is expanded without handing user text to printf.
struct FramePattern {
  std::string before, after;  // literal text ("%%" already undone)
  bool zero_pad = false;
  int width = 0;
};

FramePattern parse_pattern(const std::string& out) {
  FramePattern p;
  bool seen = false;
  const auto bad = [&] {
    return std::runtime_error("-o " + out + ": a pattern needs exactly one integer conversion such as %05d (and %% for '%')");
  };
  for (size_t i = 0; i < out.size(); ++i) {
    std::string& text = seen ? p.after : p.before;
    if (out[i] != '%') {
      text += out[i];
      continue;
    }
    if (i + 1 < out.size() && out[i + 1] == '%') {
      text += '%';
      ++i;
      continue;
    }
    if (seen) throw bad();
    seen = true;
    size_t j = i + 1;
    if (j < out.size() && out[j] == '0') p.zero_pad = true, ++j;
    while (j < out.size() && std::isdigit(static_cast<unsigned char>(out[j]))) p.width = p.width * 10 + (out[j++] - '0');
    while (j < out.size() && out[j] == 'l') ++j;
    if (j >= out.size() || (out[j] != 'd' && out[j] != 'i' && out[j] != 'u') || p.width > 20) throw bad();
    i = j;
  }
  if (!seen) throw bad();
  return p;
}

std::string expand(const FramePattern& p, uint64_t frame) {
  std::string number = std::to_string(frame);
  if (int(number.size()) < p.width) number.insert(0, size_t(p.width) - number.size(), p.zero_pad ? '0' : ' ');
  return p.before + number + p.after;
}

// Where each frame goes, and the .pvd that lists them (if any).
struct OutputPlan {
  io::ExportFormat format;
  std::map<uint64_t, std::string> files;  // by frame number
  std::string pvd;                        // empty: none
};

// OUT is a printf pattern, a single file (one frame), or names a series:
// out.vtp -> out_00000.vtp ... (frame numbers of the input) and out.pvd.
OutputPlan plan_outputs(const std::string& out, const std::vector<uint64_t>& frames) {
  const auto format = io::export_format_of(out);
  if (!format) throw std::runtime_error("-o " + out + ": the format comes from the extension: .vtp, .csv or .ply");
  OutputPlan plan{*format, {}, {}};
  const bool several = frames.size() > 1;
  std::string series_name;  // the .pvd's path without the extension
  if (out.find('%') != std::string::npos) {
    const FramePattern pattern = parse_pattern(out);
    for (uint64_t f : frames) plan.files[f] = expand(pattern, f);
    // "frames/shot_%04d.vtp" -> "frames/shot"; a pattern with no name before the number -> "series".
    const fs::path prefix(pattern.before);
    std::string name = prefix.filename().string();
    while (!name.empty() && std::string("_-. ").find(name.back()) != std::string::npos) name.pop_back();
    series_name = (prefix.parent_path() / (name.empty() ? "series" : name)).string();
  } else {
    const fs::path p(out);
    series_name = (p.parent_path() / p.stem()).string();
    for (uint64_t f : frames) {
      char number[32];
      std::snprintf(number, sizeof number, "_%05llu", (unsigned long long)f);
      plan.files[f] = several ? series_name + number + p.extension().string() : out;
    }
  }
  if (several && plan.format == io::ExportFormat::Vtp) plan.pvd = series_name + ".pvd";
  return plan;
}

// Refuses to replace files unless --force; creates the directories needed.
void prepare_outputs(const OutputPlan& plan, bool force) {
  std::vector<std::string> all;
  for (const auto& [f, path] : plan.files) all.push_back(path);
  if (!plan.pvd.empty()) all.push_back(plan.pvd);
  std::vector<std::string> existing;
  for (const std::string& path : all) {
    if (fs::exists(path)) existing.push_back(path);
  }
  if (!existing.empty() && !force) {
    const std::string more = existing.size() > 1 ? " (and " + std::to_string(existing.size() - 1) + " more outputs)" : "";
    throw std::runtime_error(existing.front() + " exists" + more + "; pass --force to overwrite, or -o to choose another name");
  }
  for (const std::string& path : all) {
    const fs::path dir = fs::path(path).parent_path();
    if (!dir.empty()) fs::create_directories(dir);
  }
}

// The indices of the requested attributes; every one when none is named.
std::vector<size_t> attribute_indices(const io::FileHeader& header, const std::vector<std::string>& names,
                                      const std::string& input) {
  std::vector<size_t> out;
  if (names.empty()) {
    for (size_t a = 0; a < header.attributes.size(); ++a) out.push_back(a);
    return out;
  }
  for (const std::string& name : names) {
    size_t a = 0;
    while (a < header.attributes.size() && header.attributes[a].name != name) ++a;
    if (a == header.attributes.size()) {
      std::string have;
      for (const auto& info : header.attributes) have += (have.empty() ? "" : ", ") + info.name;
      throw std::runtime_error(input + " has no attribute '" + name + "'; it has: " + (have.empty() ? "(none)" : have));
    }
    out.push_back(a);
  }
  return out;
}

// `file` as a .pvd at `pvd` names it: relative to the .pvd's directory.
std::string pvd_member(const std::string& pvd, const std::string& file) {
  return fs::absolute(file).lexically_relative(fs::absolute(pvd).parent_path()).generic_string();
}

// Frames decoded at once: one per core (small frames), but within a memory
// budget for big ones (a frame is decoded, then copied out as floats).
size_t frames_in_flight(const io::ContainerReader& reader, const std::vector<uint64_t>& frames, size_t attributes) {
  constexpr double kBudgetBytes = 4e9;
  uint64_t largest = 1;
  for (uint64_t f : frames) largest = std::max(largest, reader.index().frames[f].particle_count);
  const double per_particle = double(io::decoded_particle_bytes(reader.header().position_coding)) + 14.0 +
                              2.0 * double(reader.header().attributes.size()) + 4.0 * double(attributes);
  const double fit = kBudgetBytes / (per_particle * double(largest));
  return size_t(std::clamp(fit, 1.0, double(tbb::info::default_concurrency())));
}

struct FrameWritten {
  uint64_t frame = 0;
  double time = 0;
  uint64_t particles = 0, kept = 0, bytes_in = 0, bytes_out = 0;
};

// Decodes frame `f`, thins it to `lod_level` and writes its file.
FrameWritten export_frame(const io::ContainerReader& reader, uint64_t f, const std::vector<size_t>& attributes,
                          float lod_level, const OutputPlan& plan) {
  FrameWritten w;
  w.frame = f;
  w.bytes_in = reader.index().frames[f].bytes;
  io::ExportFrame frame = io::to_export_frame(io::decode_frame(reader, f), reader.header(), attributes);
  w.time = frame.time;
  w.particles = frame.count();
  if (lod_level < 1) io::thin_by_lod(frame, lod_level);
  w.kept = frame.count();
  w.bytes_out = io::write_export(plan.files.at(f), frame, plan.format);
  return w;
}

void run_export(const ExportCommand& o) {
  const io::ContainerReader reader(o.input);
  const std::vector<uint64_t> frames = parse_frame_list(o.frames, reader.frame_count());
  const std::vector<size_t> attributes = attribute_indices(reader.header(), o.attributes, o.input);
  const OutputPlan plan = plan_outputs(o.out, frames);
  prepare_outputs(plan, o.force);
  const bool thin = o.lod_level < 1;
  if (thin && !o.quiet && reader.header().lod_source == io::LodSource::ParticleOrder) {
    std::fprintf(stderr,
                 "warning: %s has LOD values from the particle order (no id array): --lod-level keeps the same\n"
                 "         particles every frame only if the solver wrote them in the same order every frame\n",
                 o.input.c_str());
  }

  // Frames are decoded, thinned and written in parallel (one file each), a
  // bounded number at a time; progress and the .pvd follow frame order.
  const uint64_t count = frames.size();
  ProgressBar bar("frames", count, o.quiet);
  std::vector<io::PvdEntry> entries;
  FrameWritten total;
  size_t next = 0;
  uint64_t done = 0;
  tbb::parallel_pipeline(
      frames_in_flight(reader, frames, attributes.size()),
      tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> uint64_t {
                                         if (next == frames.size()) {
                                           fc.stop();
                                           return 0;
                                         }
                                         return frames[next++];
                                       }) &
          tbb::make_filter<uint64_t, FrameWritten>(
              tbb::filter_mode::parallel,
              [&](uint64_t f) { return export_frame(reader, f, attributes, o.lod_level, plan); }) &
          tbb::make_filter<FrameWritten, void>(tbb::filter_mode::serial_in_order, [&](const FrameWritten& w) {
            if (!plan.pvd.empty()) entries.push_back({w.time, pvd_member(plan.pvd, plan.files.at(w.frame))});
            total.particles += w.particles;
            total.kept += w.kept;
            total.bytes_in += w.bytes_in;
            total.bytes_out += w.bytes_out;
            bar.update(++done, total.bytes_in, total.bytes_out);
          }));
  if (!plan.pvd.empty()) total.bytes_out += io::write_pvd(plan.pvd, entries);
  bar.finish();

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
