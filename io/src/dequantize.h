// Decoded particles (x, y, z, lod as uint16 against a chunk's box) into
// world-unit float32 x,y,z and the LOD values: dequantize()'s single-
// precision multiply and add, so the same floats on every path. Private to io
// (io::convert_chunk uses them; tests compare the kernels).
#pragma once

#include <cstddef>
#include <cstdint>

namespace sluice::io {

struct ChunkScale {
  float lo[3];    // the chunk box's minimum
  float step[3];  // (max - min) / 65535 per axis
};

// Particles [i, n) of `q` (4 uint16 each) into xyz (3 floats each) and lod.
void dequantize_plain(const uint16_t* q, size_t i, size_t n, const ChunkScale& s, float* xyz, uint16_t* lod);

enum class StreamingKernel {
  Sse2,  // four particles a group
  Avx2,  // eight particles a group
};
bool streaming_kernel_runs_here(StreamingKernel kernel);
// The fastest kernel this CPU runs (read once).
StreamingKernel chosen_streaming_kernel();

// For a frame larger than the caches: whole groups from particle `i` on,
// written with streaming stores (no read of the destination's lines first).
// `i` must put xyz + 3 * i on 16 bytes and lod + i on 8. Returns the
// particle after the last group; the caller does the rest with
// dequantize_plain(). Ends with a store fence.
size_t dequantize_streaming(StreamingKernel kernel, const uint16_t* q, size_t i, size_t n, const ChunkScale& s, float* xyz,
                            uint16_t* lod);

// Through the caches, four at a time where there is SSE2; each group's last
// store writes one float past it (into the next particle's x, which the
// next group or the caller then writes), so it leaves at least the last
// particle to the caller. Returns the particle after the last group.
size_t dequantize_cached(const uint16_t* q, size_t n, const ChunkScale& s, float* xyz, uint16_t* lod);

}  // namespace sluice::io
