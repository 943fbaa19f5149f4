#version 460
// Narrow band, pass 7: every particle into its voxel's list. START is the
// cursor, so afterwards a voxel's list is [START - COUNT, START) (the order
// within it does not matter).
#include "band.glsl"

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  for (uint i = first_item() + gl_LocalInvocationIndex; i < pc.n; i += round_stride()) {
    LIST(atomicAdd(START(SLOT(i)), 1u)) = i;
  }
}
