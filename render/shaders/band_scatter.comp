#version 460
// Narrow band, pass 7: every particle into its voxel's list. starts[slot]
// is the cursor, so afterwards a voxel's list is
// [starts - counts, starts) (the order within it does not matter).
#include "band.glsl"

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  for (uint i = first_item() + gl_LocalInvocationIndex; i < pc.n; i += round_stride()) {
    uint s = Uints(pc.slots).v[i];
    Uints(pc.lists).v[atomicAdd(Uints(pc.starts).v[s], 1u)] = i;
  }
}
