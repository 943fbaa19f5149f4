// `sluice bench band`: the LNM classifier against the exact narrow band on
// the input's own frames.
#include "sluice/bench/band_bench.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <optional>
#include <utility>

#include "machine.h"
#include "sluice/import/freed_memory.h"
#include "sluice/import/source.h"
#include "sluice/io/narrow_band.h"
#include "sluice/bench/synth.h"
#include "sluice/io/point_set.h"
#if SLUICE_WITH_RENDER
#include "sluice/render/band_classifier.h"
#include "sluice/render/context.h"
#endif
#include "sluice/bench/table.h"
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

#if SLUICE_WITH_RENDER
struct GpuTiming {
  double median_ms = 0;
  uint64_t differ = 0;  // particles whose layer differs from the CPU's
  std::vector<render::BandClassifier::PassTime> passes;  // each pass's median
  bool hashed = false;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// The GPU classifier's passes (timestamps, the upload left out), warmed up
// and repeated for at least `min_seconds` of wall time and 5 runs; blobs on,
// as a renderer classifying a frame needs them.
GpuTiming timed_gpu_classify(render::BandClassifier& gpu, const io::ParticleFrame& f, io::NarrowBandOptions o,
                             const io::NarrowBand& cpu, double min_seconds) {
  o.blobs = true;
  GpuTiming t;
  const io::NarrowBand band = gpu.classify(f.positions, o);
  for (size_t i = 0; i < band.layer.size(); ++i) t.differ += band.layer[i] != cpu.layer[i];
  std::vector<double> ms;
  std::vector<std::vector<double>> pass_ms;
  const auto start = std::chrono::steady_clock::now();
  while (ms.size() < 5 || std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < min_seconds) {
    (void)gpu.classify(f.positions, o);
    ms.push_back(gpu.last_gpu_ms());
    const auto passes = gpu.last_pass_ms();
    pass_ms.resize(passes.size());
    for (size_t p = 0; p < passes.size(); ++p) pass_ms[p].push_back(passes[p].ms);
  }
  t.median_ms = median(ms);
  t.hashed = gpu.last_hashed();
  for (size_t p = 0; p < pass_ms.size(); ++p) t.passes.push_back({gpu.last_pass_ms()[p].name, median(pass_ms[p])});
  return t;
}
#endif

}  // namespace

void run_band_bench(const BandBenchOptions& o) {
  const import::KeepFreedMemory keep;  // as `sluice convert` classifies: frame buffers reused, not faulted in again
  const int cores = o.max_threads > 0 ? o.max_threads : core_count();
  std::unique_ptr<import::FrameSource> source;
  if (o.synth > 0) {
    SynthOptions so;
    so.particles = o.synth;
    so.frames = 1;
    source = synthetic_source(so);
  } else {
    source = import::open_source(o.input, {});
  }
  std::printf("sluice bench band: %s\nmachine: %s, %d threads\n", source->info().description.c_str(),
              cpu_model().c_str(), cores);
#if SLUICE_WITH_RENDER
  std::unique_ptr<render::Context> context;
  std::unique_ptr<render::BandClassifier> gpu;
  if (o.gpu) {
    render::ContextOptions co;
    co.device = o.device;
    context = std::make_unique<render::Context>(co);
    gpu = std::make_unique<render::BandClassifier>(*context);
    std::printf("gpu: %s (%s)\n", context->device().name.c_str(), context->device().driver.c_str());
  }
#else
  if (o.gpu) throw io::Error({}, "bench band --gpu: this build has no renderer (SLUICE_WITH_RENDER off)");
  const bool gpu = false;
#endif
  std::vector<std::string> columns{"frame", "particles", "h", "surface (L1 + L2 + isolated)", "kept", "1 thread M/s",
                                   std::to_string(cores) + " threads M/s"};
  if (gpu) columns.insert(columns.end(), {"GPU ms", "GPU M/s", "GPU differs from CPU"});
  Table speed(columns);
  std::optional<Table> passes;
  Table layers({"frame", "layer", "particles", "exact narrow band", "share of the exact band", "LNM surface"});
  Table agree({"frame", "F2", "exact band", "LNM surface", "kept", "exact band found by LNM", "LNM surface not in exact band"});
  for (const uint64_t f : picked_frames(source->frame_count(), o.frames)) {
    const io::ParticleFrame frame = source->read(f);
    const size_t n = frame.count();
    if (n < 2) continue;
    const float h = o.diameter > 0 ? o.diameter : io::estimate_spacing(frame.positions);
    const io::NarrowBandOptions options{.diameter = h};
    const io::NarrowBand band = io::classify_narrow_band(frame.positions, options);
    const double one = timed_classify(frame, options, 1, o.min_seconds);
    const double all = timed_classify(frame, options, cores, o.min_seconds);
    std::vector<std::string> row{std::to_string(f), std::to_string(n), fixed(h, 4),
                                 std::to_string(band.counts[1]) + " + " + std::to_string(band.counts[2]) + " + " +
                                     std::to_string(band.counts[3]),
                                 fixed(100.0 * double(band.surface()) / double(n), 1) + "%", fixed(double(n) / one / 1e6, 1),
                                 fixed(double(n) / all / 1e6, 1)};
#if SLUICE_WITH_RENDER
    if (gpu) {
      const GpuTiming t = timed_gpu_classify(*gpu, frame, options, band, o.min_seconds);
      row.insert(row.end(), {fixed(t.median_ms, 3), fixed(double(n) / t.median_ms / 1e3, 1), std::to_string(t.differ)});
      if (!t.passes.empty()) {
        if (!passes) {
          std::vector<std::string> names{"frame", "particles", "voxels"};
          for (const auto& p : t.passes) names.push_back(std::string(p.name) + " ms");
          names.push_back("positions read at (GB/s, the bounds pass)");
          passes.emplace(names);
        }
        std::vector<std::string> cells{std::to_string(f), std::to_string(n), t.hashed ? "hashed" : "by cell"};
        for (const auto& p : t.passes) cells.push_back(fixed(p.ms, 3));
        cells.push_back(fixed(double(n) * 12 / (t.passes[1].ms * 1e-3) / 1e9, 1));
        passes->row(cells);
      }
    }
#endif
    speed.row(row);

    if (!o.exact) continue;
    const std::vector<bool> exact = io::exact_narrow_band(frame.positions, h);
    const std::vector<uint8_t> layer = io::voxel_layers(frame.positions, band.voxel);
    std::array<uint64_t, 6> in_layer{}, exact_in_layer{}, lnm_in_layer{};
    uint64_t exact_total = 0;
    for (size_t i = 0; i < n; ++i) {
      const size_t l = std::min<size_t>(layer[i], 5);
      ++in_layer[l];
      exact_in_layer[l] += exact[i];
      lnm_in_layer[l] += io::is_surface(band.layer[i]);
      exact_total += exact[i];
    }
    for (size_t l = 1; l < in_layer.size(); ++l) {
      if (in_layer[l] == 0) continue;
      char name[8];
      std::snprintf(name, sizeof name, l == 5 ? "L%zu+" : "L%zu", l);
      layers.row({std::to_string(f), name, std::to_string(in_layer[l]),
                  std::to_string(exact_in_layer[l]),
                  fixed(exact_total ? 100.0 * double(exact_in_layer[l]) / double(exact_total) : 0.0, 2) + "%",
                  std::to_string(lnm_in_layer[l])});
    }
    // Both F2 tests the dissertation compares: every particle of a selected
    // L2 voxel (the default) and the asymmetry test.
    const io::NarrowBand asymmetric = io::classify_narrow_band(frame.positions, {.diameter = h, .f2 = io::F2Test::Asymmetry});
    for (const auto& [name, lnm] : {std::pair{"every particle", &band}, std::pair{"asymmetry", &asymmetric}}) {
      uint64_t found = 0, extra = 0;
      for (size_t i = 0; i < n; ++i) {
        found += exact[i] && io::is_surface(lnm->layer[i]);
        extra += !exact[i] && io::is_surface(lnm->layer[i]);
      }
      agree.row({std::to_string(f), name, std::to_string(exact_total), std::to_string(lnm->surface()),
                 fixed(100.0 * double(lnm->surface()) / double(n), 1) + "%",
                 fixed(exact_total ? 100.0 * double(found) / double(exact_total) : 100.0, 2) + "%", std::to_string(extra)});
    }
  }
  speed.print(gpu ? "LNM classification (voxel 2h, F2 = every particle of a selected L2 voxel); GPU: median of its "
                    "passes with blobs, upload and read-back left out"
                  : "LNM classification (voxel 2h, F2 = every particle of a selected L2 voxel)");
  if (passes) passes->print("GPU classification pass by pass (medians)");
  if (!o.exact) return;
  layers.print("The exact narrow band by voxel layer (the LNM dissertation's tables 1 and 2)");
  agree.print("LNM against the exact narrow band (spheres of radius h, 64 directions)");
}

}  // namespace sluice::bench
