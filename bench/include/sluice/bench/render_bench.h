// sluice/bench/render_bench.h: `sluice bench render`, GPU time per pass of
// the renderer at a given resolution for synthetic frames of 1M..100M
// particles (and a real file), with cLOD off and on; optionally side by side
// with VTK 9's vtkOpenGLFluidMapper on the same frame, camera and size.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sluice::bench {

struct RenderBenchOptions {
  std::vector<uint64_t> sizes{1'000'000, 10'000'000, 50'000'000, 100'000'000};  // synthetic particle counts
  uint32_t width = 1920, height = 1080;
  int repeats = 3;              // renders per case; the median is reported
  float lod_level = 0.3f;       // the "LOD on" rows (density-preserving cLOD)
  std::string real;             // a .sluice file: its last frame gets rows too
  bool vtk = false;             // run the VTK peer (python3-vtk9 under xvfb-run)
  uint64_t vtk_max = 1'000'000; // largest frame given to the peer (it takes ~30 s per frame per 1M on llvmpipe)
  // The native peer (bench/vtk_peer: VTK built with EGL, headless on a GPU
  // driver) instead of python3-vtk9 under xvfb-run; empty: the Python peer.
  std::string vtk_peer;
  std::string device;           // Vulkan device choice, as --device
  std::string images;           // directory to save each case's image (and the peer's)
  std::string splat = "auto";   // sphere splatting: auto, compute or raster
  std::string csv;              // also write every case (per-pass ms) here, for plots of ms against particles
  std::string plot;             // also draw GPU ms against particles (log-log, one line per LOD) as an SVG here
  // Also draw each synthetic frame classified into the narrow band's layers
  // (encoded as `sluice convert` writes it): its surface and voxel blobs,
  // and all its particles from the same chunks, for the narrow band's saving.
  bool layers = false;
  bool with_depth = false;      // render into a target with a depth image, as a host with its own geometry does
                                // (shading tests and writes it, through two copies; without, shading writes the image)
  // Synthetic frames in Morton order, one chunk row per block, as files
  // without LOD tiers are (default: tiered as `sluice convert` writes them).
  bool untiered = false;
  bool present_pass = false;    // with_depth: a depth image without transfer usage, so the present pass draws into it
  bool keep_depth = false;      // with_depth: each frame starts from the last one's depth, as a host's drawn depth
  // Stereo rows instead of mono ones: two eyes of width x height each (64 mm
  // apart for data shown 1.5 m across), both in one pass into a 2-layer
  // target, against the same two views as two mono passes side by side.
  bool stereo = false;
  // Also draw each frame with anisotropic particles (RendererOptions::
  // anisotropic): rows named ", ellipsoids", with the ellipsoids' own pass
  // (computed once per frame, at its first draw) in a column of its own.
  bool ellipsoids = false;
};

// Runs the benchmark and prints its tables to stdout.
void run_render_bench(const RenderBenchOptions& options);

// Parses "1M,10M,2.5k,1000" into counts. Throws std::invalid_argument.
std::vector<uint64_t> parse_counts(const std::string& text);

}  // namespace sluice::bench
