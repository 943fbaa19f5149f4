// `sluice synth`: a synthetic fluid sequence for scale runs (10M particles x
// 200 frames and up) without any solver output at hand.
#include <cctype>
#include <cmath>
#include <filesystem>

#include "commands.h"
#include "format_option.h"
#include "human.h"
#include "progress.h"
#include "sluice/bench/synth.h"

namespace sluice::app {
namespace {

// "10M", "2.5M", "500k", "1G", "12000": counts use decimal multiples.
uint64_t parse_count(const std::string& text) {
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  double scale = 1;
  if (used > 0 && used + 1 == text.size()) {
    switch (std::toupper(static_cast<unsigned char>(text.back()))) {
      case 'K': scale = 1e3; break;
      case 'M': scale = 1e6; break;
      case 'G': scale = 1e9; break;
      default: used = 0;
    }
  } else if (used != text.size()) {
    used = 0;
  }
  if (used == 0 || !(value > 0) || value * scale > 9e18) {
    throw CLI::ValidationError("-n", "'" + text + "' is not a particle count (try 1000000, 10M or 500k)");
  }
  return static_cast<uint64_t>(std::llround(value * scale));
}

}  // namespace

void add_synth(CLI::App& app) {
  auto o = std::make_shared<bench::SynthOptions>();
  auto count = std::make_shared<std::string>("1M");
  auto motion = std::make_shared<std::string>("slosh");
  auto force = std::make_shared<bool>(false);
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("synth", "Write a synthetic fluid sequence (for scale runs and benchmarks)");
  cmd->footer("Example: sluice synth -n 10M --frames 200 -o synth.sluice\n"
              "Particles keep their ids from frame to frame, so LOD values are stable.");
  cmd->add_option("-n,--particles", *count, "Particles per frame: 1000000, 10M, 500k")->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames")->capture_default_str();
  cmd->add_option("-o,--output", o->output, ".sluice file to write")->required();
  cmd->add_option("--motion", *motion, "slosh (a wave block in a tank) or lattice (a drifting jittered lattice)")
      ->capture_default_str()
      ->check(CLI::IsMember({"slosh", "lattice"}));
  cmd->add_option("--fps", o->frame_rate, "Frame rate stored in the file")->capture_default_str();
  cmd->add_option("--spacing", o->spacing, "Particle spacing, world units")->capture_default_str();
  cmd->add_flag("--speed", o->speed_attribute, "Add a 'speed' attribute stream");
  cmd->add_flag("--lossless", o->lossless, "Store float32 positions instead of 16-bit quantized");
  cmd->add_option("--chunk", o->chunk_particles, "Most particles per chunk")->capture_default_str();
  cmd->add_option("--level", o->zstd_level, "zstd level")->capture_default_str();
  cmd->add_flag("--no-layers", [o](int64_t) { o->layers = false; },
                "Do not classify the narrow band: every frame one layer of all its particles");
  cmd->add_option_function<double>(
         "--precision", [o](double p) { o->precision_bits = io::precision_bits_for(p); },
         "Largest position error as a fraction of the spacing, rounded down to a power of two (default 1/1024)")
      ->check(CLI::Range(1e-12, 0.5));
  add_format_option(*cmd, o->format_major);
  cmd->add_flag("--no-tiers", [o](int64_t) { o->lod_tiers = false; },
                "One record per chunk, not one per LOD tier (format 1.3's layout): smaller, always read whole");
  cmd->add_flag("--smallest", [o](int64_t) { o->planes = io::PlaneCoding::Zstd; },
                "zstd on every plane it shrinks most (smaller, slower to decode)");
  cmd->add_flag("--gpu-decodable", [o](int64_t) { o->planes = io::PlaneCoding::GpuDecodable; },
                "No zstd planes (each stored or bit-packed): every chunk decodes on the GPU with no CPU work\n"
                "but its checksum; files some percent larger (docs/format.md)");
  cmd->add_option("-j,--jobs", o->jobs, "Frames encoded at once (default: one per core)");
  cmd->add_option("--seed", o->seed, "Seed of the particles' jitter")->capture_default_str();
  cmd->add_flag("-f,--force", *force, "Overwrite the output");
  cmd->add_flag("-q,--quiet", *quiet, "No progress bar");
  cmd->callback([=] {
    o->particles = parse_count(*count);
    o->motion = *motion == "lattice" ? bench::SynthMotion::Lattice : bench::SynthMotion::Slosh;
    if (std::filesystem::exists(o->output) && !*force) {
      throw std::runtime_error(o->output + " exists; pass --force to overwrite it");
    }
    if (!*quiet) {
      std::fprintf(stderr, "writing %s: %llu frames of %s particles (%s)\n", o->output.c_str(),
                   (unsigned long long)o->frames, human_count(double(o->particles)).c_str(), motion->c_str());
    }
    ProgressBar bar("frames", o->frames, *quiet);
    const bench::SynthResult r = bench::write_synthetic(
        *o, [&](uint64_t done, uint64_t bytes) { bar.update(done, done * o->particles * 12, bytes); });
    bar.finish();
    std::printf("wrote %s: %llu frames, %s particles each, %s (%s bytes/particle) in %s\n", o->output.c_str(),
                (unsigned long long)r.frames, human_count(double(o->particles)).c_str(), human_bytes(double(r.bytes)).c_str(),
                fixed(double(r.bytes) / double(r.particles), 2).c_str(), human_duration(bar.elapsed()).c_str());
  });
}

}  // namespace sluice::app
