// `sluice bench band`: the LNM classifier against the exact narrow band on
// the input's own frames.
#include "sluice/bench/band_bench.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <optional>

#include "machine.h"
#include "sluice/io/freed_memory.h"
#include "sluice/io/import.h"
#include "sluice/io/narrow_band.h"
#include "sluice/bench/synth.h"
#include "sluice/io/spacing.h"
#include "table.h"
#include "timing.h"

namespace sluice::bench {
namespace {

std::vector<uint64_t> picked_frames(uint64_t count, int wanted) {
  std::vector<uint64_t> out;
  const uint64_t n = std::min<uint64_t>(count, uint64_t(std::max(1, wanted)));
  for (uint64_t k = 0; k < n; ++k) out.push_back(n == 1 ? 0 : k * (count - 1) / (n - 1));
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

double timed_classify(const io::ParticleFrame& f, const io::NarrowBandOptions& o, int threads, double min_seconds) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  return seconds_per_pass(min_seconds, [&] { (void)io::classify_narrow_band(f.positions, o); });
}

}  // namespace

void run_band_bench(const BandBenchOptions& o) {
  const io::KeepFreedMemory keep;  // as `sluice convert` classifies: frame buffers reused, not faulted in again
  const int cores = o.max_threads > 0 ? o.max_threads : core_count();
  std::unique_ptr<io::FrameSource> source;
  if (o.synth > 0) {
    SynthOptions so;
    so.particles = o.synth;
    so.frames = 1;
    source = synthetic_source(so);
  } else {
    source = io::open_source(o.input, {});
  }
  std::printf("sluice bench band: %s\nmachine: %s, %d threads\n", source->info().description.c_str(),
              cpu_model().c_str(), cores);
  Table speed({"frame", "particles", "h", "surface (L1 + L2 + isolated)", "kept", "1 thread M/s",
               std::to_string(cores) + " threads M/s"});
  Table layers({"frame", "layer", "particles", "exact narrow band", "share of the exact band", "LNM surface"});
  Table agree({"frame", "exact band", "LNM surface", "exact band found by LNM", "LNM surface not in exact band"});
  for (const uint64_t f : picked_frames(source->frame_count(), o.frames)) {
    const io::ParticleFrame frame = source->read(f);
    const size_t n = frame.count();
    if (n < 2) continue;
    const float h = o.diameter > 0 ? o.diameter : io::estimate_spacing(frame.positions);
    const io::NarrowBandOptions options{.diameter = h};
    const io::NarrowBand band = io::classify_narrow_band(frame.positions, options);
    const double one = timed_classify(frame, options, 1, o.min_seconds);
    const double all = timed_classify(frame, options, cores, o.min_seconds);
    speed.row({std::to_string(f), std::to_string(n), num(h, 4),
               std::to_string(band.counts[1]) + " + " + std::to_string(band.counts[2]) + " + " +
                   std::to_string(band.counts[3]),
               num(100.0 * double(band.surface()) / double(n), 1) + "%", num(double(n) / one / 1e6, 1),
               num(double(n) / all / 1e6, 1)});

    if (!o.exact) continue;
    const std::vector<bool> exact = io::exact_narrow_band(frame.positions, h);
    const std::vector<uint8_t> layer = io::voxel_layers(frame.positions, band.voxel);
    std::array<uint64_t, 6> in_layer{}, exact_in_layer{}, lnm_in_layer{};
    uint64_t exact_total = 0, found = 0, extra = 0;
    for (size_t i = 0; i < n; ++i) {
      const size_t l = std::min<size_t>(layer[i], 5);
      ++in_layer[l];
      exact_in_layer[l] += exact[i];
      lnm_in_layer[l] += io::is_surface(band.layer[i]);
      exact_total += exact[i];
      found += exact[i] && io::is_surface(band.layer[i]);
      extra += !exact[i] && io::is_surface(band.layer[i]);
    }
    for (size_t l = 1; l < in_layer.size(); ++l) {
      if (in_layer[l] == 0) continue;
      char name[8];
      std::snprintf(name, sizeof name, l == 5 ? "L%zu+" : "L%zu", l);
      layers.row({std::to_string(f), name, std::to_string(in_layer[l]),
                  std::to_string(exact_in_layer[l]),
                  num(exact_total ? 100.0 * double(exact_in_layer[l]) / double(exact_total) : 0.0, 2) + "%",
                  std::to_string(lnm_in_layer[l])});
    }
    agree.row({std::to_string(f), std::to_string(exact_total), std::to_string(band.surface()),
               num(exact_total ? 100.0 * double(found) / double(exact_total) : 100.0, 2) + "%", std::to_string(extra)});
  }
  speed.print("LNM classification (voxel 2h, F2 = every particle of a selected L2 voxel)");
  if (!o.exact) return;
  layers.print("The exact narrow band by voxel layer (the LNM dissertation's tables 1 and 2)");
  agree.print("LNM against the exact narrow band (spheres of radius h, 64 directions)");
}

}  // namespace sluice::bench
