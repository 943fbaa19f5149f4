// sluice/bench/layers_bench.h: `sluice bench layers`, the narrow band's
// picture against every particle's on a file with layers (format 1.3): the
// same frame drawn from its surface and blobs and from all its particles,
// from several viewpoints, compared by PSNR and fluid coverage, with the
// bytes each reads and the GPU time each takes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sluice::bench {

struct LayersBenchOptions {
  std::string input;             // a .sluice file written with layers (`sluice convert` does by default)
  std::vector<uint64_t> frames;  // empty: the last
  uint32_t width = 1280, height = 720;
  std::string device;            // Vulkan device: index or part of its name
  bool validation = false;       // run with the validation layer (tests)
  int repeats = 5;               // renders per case for the GPU time (median)
  std::string images;            // directory to save every image in; empty: none
  // The narrow band classified on the GPU instead of read from the file:
  // the frame is loaded whole into a renderer that classifies frames
  // without layers (RendererOptions::classify_unlayered); the file may then
  // have no layers.
  bool gpu = false;
};

// One view of one frame, both ways.
struct LayersRow {
  std::string view;  // above, grazing, splash, close-up, default
  uint64_t frame = 0;
  double psnr = 0;   // dB, surface + blobs against all particles (infinity when identical)
  // Fluid pixels (those that differ from the same view without particles),
  // as fractions of the image.
  double coverage_all = 0, coverage_surface = 0;
  uint64_t drawn_all = 0, drawn_surface = 0;    // particles (and blobs) after culling
  double gpu_ms_all = 0, gpu_ms_surface = 0;    // medians (the classification left out)
  double classify_ms = 0;                       // with options.gpu: the classification, once per frame
  std::string classification;                   // with options.gpu: render::describe() of it (first view of a frame)
  uint64_t bytes_all = 0, bytes_surface = 0;    // of the record each reads
  uint64_t validation_errors = 0;               // with options.validation
  // The largest particle splat of the view (pixels across, every particle in
  // front of the eye) against the largest the renderer draws: beyond it the
  // nearest particles are culled (thesis 3.4), and where surface particles
  // go, the narrow band shows the hollow the interior left (docs/narrow_band.md).
  double largest_splat_px = 0, splat_limit_px = 0;
  bool near_cull() const { return largest_splat_px > splat_limit_px; }
};

// Renders every view of every frame both ways. Throws io::Error on a bad
// file, std::runtime_error when the file has no layers (without gpu).
std::vector<LayersRow> compare_layers(const LayersBenchOptions& options);

// compare_layers(), printed as a table on stdout.
void run_layers_bench(const LayersBenchOptions& options);

}  // namespace sluice::bench
