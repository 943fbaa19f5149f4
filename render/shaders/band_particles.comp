#version 460
// Narrow band, pass 8: every particle's layer (io::BandLayer): L1 or
// selected L2 by its voxel (F2: every particle), isolated when its voxel
// holds at most 2 and no other particle lies nearer than the reach.
#include "band.glsl"

shared uint s_counts[4];

// The particles of slot s: [first, end) of the lists.
uvec2 list_of(uint s) {
  uint end = START(s);
  return uvec2(end - COUNT(s), end);
}

bool none_near(uint s, uint i, vec3 p) {
  if (s == kEmpty) return true;
  uvec2 range = list_of(s);
  for (uint k = range.x; k < range.y; ++k) {
    uint j = LIST(k);
    if (j == i) continue;
    vec3 q = particle(j);
    precise float d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      precise float d = p[a] - q[a];
      d2 += d * d;
    }
    if (d2 < pc.reach2) return false;
  }
  return true;
}

bool alone(uint s, uint i, Params g) {
  vec3 p = particle(i);
  if (!none_near(s, i, p)) return false;
  uvec3 c = cell_of_key(key_of_slot(s, g), g);
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        if (!none_near(neighbour_slot(c, ivec3(dx, dy, dz), g), i, p)) return false;
      }
  return true;
}

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  if (gl_LocalInvocationIndex < 4u) s_counts[gl_LocalInvocationIndex] = 0u;
  barrier();
  uint counts[4] = uint[4](0u, 0u, 0u, 0u);
  for (uint i = first_item() + gl_LocalInvocationIndex; i < pc.n; i += round_stride()) {
    uint s = SLOT(i);
    uint layer = L1MARK(s) != 0u ? 1u : L2MARK(s) != 0u ? 2u : 0u;
    if (COUNT(s) <= 2u && alone(s, i, g)) layer = 3u;
    LAYER(i) = layer;
    ++counts[layer];
  }
  for (int l = 0; l < 4; ++l) {
    if (counts[l] > 0u) atomicAdd(s_counts[l], counts[l]);
  }
  barrier();
  if (gl_LocalInvocationIndex < 4u && s_counts[gl_LocalInvocationIndex] > 0u) {
    atomicAdd(g.counts[gl_LocalInvocationIndex], s_counts[gl_LocalInvocationIndex]);
  }
}
