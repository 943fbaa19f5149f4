// sluice/bench/view_bench.h: `sluice bench view`, reading only what the view
// draws (LOD tiers, runtime/demand.h) against reading every tier of the
// surface and blobs (the full read), on one scripted camera path, measured
// side by side in one run.
//
// The path: an orbit of the overview (a quarter turn), a fly-in to a
// close-up inside the pool with part of it outside the view, and a pause on
// the overview during which the LOD level rises to 1 (the picture must
// converge to the full read's). Each segment is played as fast as frames
// arrive (every frame due at once, none skipped) through the players' own
// path (Player -> FrameFeed -> Renderer; one renderer, warmed up first, for
// every run), from storage with the file dropped from the page cache and
// from the page cache; each player reads by its first step's demand from
// its start, and is timed from its start. Printed per segment and read:
// frames/s, bytes read per frame and their share of the whole records, and
// the PSNR of each streamed picture against the full read of the same frame
// and view (a separate pass, not timed). Tables only: nothing passes or fails.
#pragma once

#include <cstdint>
#include <string>

#include "sluice/render/options.h"

namespace sluice::bench {

struct ViewBenchOptions {
  std::string file;
  uint32_t width = 1920, height = 1080;  // per eye with `stereo`
  bool stereo = false;                   // both eyes in one pass (a headset-sized view: --size 2064x2208)
  std::string lod = "clod";              // clod | density
  float level = 0.3f;
  // Precision by distance (render::LodOptions::position_error_pixels; 0:
  // positions always at full precision).
  float position_error = render::LodOptions{}.position_error_pixels;
  uint64_t memory = 0;                   // the pipeline's memory cap; 0: 4 GiB
  uint32_t steps = 48;                   // frames of the orbit and of the fly-in each
  // The same from the page cache, where the file may loop (more frames than
  // it has give steadier rates); 0: `steps`.
  uint32_t cache_steps = 0;
  bool storage = true;                   // also from storage (drops the file from the page cache)
  bool psnr = true;                      // the quality pass
  std::string decode = "auto";           // auto | cpu | gpu
  std::string device;                    // Vulkan device ("": the first GPU)
  int read_threads = 0;                  // the pipeline's (ReadSettings::threads); 0: its default
  int read_rounds = 0;                   // records read at once (ReadSettings::rounds); 0: the pipeline's default
  bool mapped_reads = true;              // false: pread (ReadSettings::mapped)
  bool direct_io = false;                // O_DIRECT reads (ReadSettings::direct_io)
  // Only the close-up's read share (no timed segments, no pictures): what a
  // layout's cells leave out of a close view, quick to compare.
  bool close_up_only = false;
};

// Throws io::Error on a bad file.
void run_view_bench(const ViewBenchOptions& options);

}  // namespace sluice::bench
