#version 460
// Narrow band, pass 6: selected L2 voxels, next to an L1 voxel holding at
// most n1 particles (too few to hide what lies behind it). Its marks go to
// words no invocation of this pass reads.
#include "band.glsl"

shared uint s_l2;

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  uint voxels = g.voxels;
  if (gl_LocalInvocationIndex == 0u) s_l2 = 0u;
  barrier();
  for (uint v = first_item() + gl_LocalInvocationIndex; v < voxels; v += round_stride()) {
    uint s = VOXEL(v);
    if (L1MARK(s) != 0u) continue;
    uvec3 c = cell_of_key(key_of_slot(s, g), g);
    bool selected = false;
    for (int dx = -1; dx <= 1 && !selected; ++dx)
      for (int dy = -1; dy <= 1 && !selected; ++dy)
        for (int dz = -1; dz <= 1 && !selected; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          uint w = neighbour_slot(c, ivec3(dx, dy, dz), g);
          selected = w != kEmpty && L1MARK(w) != 0u && COUNT(w) <= pc.n1;
        }
    if (selected) {
      L2MARK(s) = 1u;
      atomicAdd(s_l2, 1u);
    }
  }
  barrier();
  if (gl_LocalInvocationIndex == 0u && s_l2 > 0u) atomicAdd(g.l2, s_l2);
}
