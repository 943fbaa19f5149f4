#version 460
// Narrow band, pass 3: every particle into its voxel's slot (hashed: the
// key inserted by the first particle to reach it), counted there.
#include "band.glsl"

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  for (uint i = first_item() + gl_LocalInvocationIndex; i < pc.n; i += round_stride()) {
    uint key = key_of(cell_of(particle(i), g), g);
    uint s = g.dense != 0u ? key : hash_key(key) & pc.mask;
    while (g.dense == 0u) {
      // A slot's key never changes once set: a plain read that finds it
      // saves the atomic (most particles share their voxel with others).
      uint seen = KEY(s);
      if (seen == key) break;
      if (seen == kEmpty) {
        seen = atomicCompSwap(KEY(s), kEmpty, key);
        if (seen == kEmpty || seen == key) break;
      }
      s = (s + 1u) & pc.mask;
    }
    atomicAdd(COUNT(s), 1u);
    SLOT(i) = s;
  }
}
