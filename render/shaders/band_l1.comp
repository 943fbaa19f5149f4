#version 460
// Narrow band, pass 5: L1 voxels, those with an empty (or outside) voxel
// among their 26 neighbours.
#include "band.glsl"

shared uint s_l1;

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  uint voxels = g.voxels;
  if (gl_LocalInvocationIndex == 0u) s_l1 = 0u;
  barrier();
  for (uint v = first_item() + gl_LocalInvocationIndex; v < voxels; v += round_stride()) {
    uint s = VOXEL(v);
    uvec3 c = cell_of_key(key_of_slot(s, g), g);
    bool l1 = false;
    for (int dx = -1; dx <= 1 && !l1; ++dx)
      for (int dy = -1; dy <= 1 && !l1; ++dy)
        for (int dz = -1; dz <= 1 && !l1; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          l1 = neighbour_slot(c, ivec3(dx, dy, dz), g) == kEmpty;
        }
    if (l1) {
      L1MARK(s) = 1u;
      atomicAdd(s_l1, 1u);
    }
  }
  barrier();
  if (gl_LocalInvocationIndex == 0u && s_l1 > 0u) atomicAdd(g.l1, s_l1);
}
