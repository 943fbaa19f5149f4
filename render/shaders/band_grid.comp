#version 460
// Narrow band, pass 2 (one invocation): the voxel grid over the box, with
// the float operations io::classify_narrow_band uses.
#include "band.glsl"

float unordered(uint u) {
  return uintBitsToFloat((u & 0x80000000u) != 0u ? u & 0x7fffffffu : ~u);
}

void main() {
  if (gl_GlobalInvocationID.x != 0u) return;
  Params g = Params(pc.params);
  const float kAxisCells = 1048576.0;  // io's limit per axis
  for (int a = 0; a < 3; ++a) {
    // No finite coordinate on this axis: the CPU's empty box.
    bool empty = g.lo[a] > g.hi[a];
    float lo = empty ? 3.40282347e38 : unordered(g.lo[a]);
    float hi = empty ? -3.40282347e38 : unordered(g.hi[a]);
    precise float extent = hi >= lo ? hi - lo : 0.0;
    precise float scaled = extent * pc.inverse;
    precise float cells = floor(scaled + 0.25);
    if (isnan(cells)) cells = 0.0;  // 0 x an overflowed inverse, as the CPU takes it
    g.dims[a] = uint(min(cells + 3.0, kAxisCells));
    precise float quarter = 0.25 * pc.side;
    precise float origin = lo - quarter;
    g.origin[a] = origin;
    g.last_cell[a] = float(g.dims[a] - 3u);
  }
  // Keys are linear cells in 32 bits, kEmpty excluded.
  uint high, low, high2, low2;
  umulExtended(g.dims[0], g.dims[1], high, low);
  umulExtended(low, g.dims[2], high2, low2);
  g.fits = high == 0u && high2 == 0u && low2 != 0xffffffffu ? 1u : 0u;
  g.cells = g.fits != 0u ? low2 : 0u;
  g.dense = g.fits != 0u && low2 <= pc.mask ? 1u : 0u;
}
