#version 460
// Narrow band, pass 3: every particle into its voxel's slot of the hash
// table (inserted by the first particle to reach it), counted there.
#include "band.glsl"

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  Uints keys = Uints(pc.keys);
  for (uint i = first_item() + gl_LocalInvocationIndex; i < pc.n; i += round_stride()) {
    uint key = key_of(cell_of(particle(i), g), g);
    uint s = hash_key(key) & pc.mask;
    for (;;) {
      uint before = atomicCompSwap(keys.v[s], kEmpty, key);
      if (before == kEmpty || before == key) break;
      s = (s + 1u) & pc.mask;
    }
    atomicAdd(Uints(pc.counts).v[s], 1u);
    Uints(pc.slots).v[i] = s;
  }
}
