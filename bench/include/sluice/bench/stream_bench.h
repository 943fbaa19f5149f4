// sluice/bench/stream_bench.h: `sluice bench stream`, the streaming pipeline
// against the machine's own bounds, measured in the same run.
//
// Prints: the bounds (memcpy on one and on all threads; sequential pread of
// the file from storage with the page cache bypassed, and from the page
// cache), the pipeline's sustained frames/s and GB/s from storage and from
// the page cache with each figure as a ratio of the slower bound, and a
// decode scaling table for 1..N workers. Tables only: nothing passes or fails.
#pragma once

#include <cstdint>
#include <string>

namespace sluice::bench {

struct StreamBenchOptions {
  std::string file;
  int max_threads = 0;       // decode workers at most; 0: all cores
  int read_threads = 0;      // the pipeline's read threads (and the read bounds'); 0: its default
  double min_seconds = 3.0;  // each page-cache timing runs at least this long
  uint64_t memory = 0;       // the pipeline's memory cap; 0: 2 GiB
  uint64_t frames = 0;       // frames to stream (from frame 0); 0: as many as fit in the page cache
  bool storage = true;       // also measure from storage (drops the file from the page cache)
  bool surface = false;      // the pipeline reads the surface and blobs of a file with layers (format 1.3)
  std::string device;        // --gpu: the Vulkan device (render::ContextOptions::device; "": the first GPU)
  // --gpu: the relayed row's ring (render::StagingOptions; 0: its defaults).
  uint32_t ring_slots = 0;
  uint64_t ring_piece_bytes = 0;
  bool ring_imported = false;  // the ring in imported anonymous memory (render::RingMemory::Imported)
};

// Throws io::Error on a bad file.
void run_stream_bench(const StreamBenchOptions& options);

// `sluice bench stream --gpu` (builds with the renderer): frames arriving
// decoded in device memory. Prints the bounds measured in the same run
// (page-cache read, host-to-device copy, GPU decode alone with the frame
// resident), then the pipeline into the renderer's device buffers with the
// GPU decoding (frames kept encoded) and, beside it, with the CPU decoding,
// each as frames/s, a share of the slower bound, and the CPU time per frame.
void run_stream_gpu_bench(const StreamBenchOptions& options);

}  // namespace sluice::bench
