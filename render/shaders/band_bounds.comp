#version 460
// Narrow band, pass 1: the particles' bounding box (finite coordinates only),
// as order-preserving uints so that integer atomics find it.
#include "band.glsl"

shared uint s_lo[3], s_hi[3];

uint ordered(float f) {
  uint b = floatBitsToUint(f);
  return (b & 0x80000000u) != 0u ? ~b : b | 0x80000000u;
}

void main() {
  if (gl_LocalInvocationIndex < 3u) {
    s_lo[gl_LocalInvocationIndex] = 0xffffffffu;
    s_hi[gl_LocalInvocationIndex] = 0u;
  }
  barrier();
  uint lo[3] = uint[3](0xffffffffu, 0xffffffffu, 0xffffffffu);
  uint hi[3] = uint[3](0u, 0u, 0u);
  for (uint i = first_item() + gl_LocalInvocationIndex; i < pc.n; i += round_stride()) {
    vec3 p = particle(i);
    for (int a = 0; a < 3; ++a) {
      if (isinf(p[a]) || isnan(p[a])) continue;
      lo[a] = min(lo[a], ordered(p[a]));
      hi[a] = max(hi[a], ordered(p[a]));
    }
  }
  for (int a = 0; a < 3; ++a) {
    atomicMin(s_lo[a], lo[a]);
    atomicMax(s_hi[a], hi[a]);
  }
  barrier();
  if (gl_LocalInvocationIndex < 3u) {
    Params g = Params(pc.params);
    atomicMin(g.lo[gl_LocalInvocationIndex], s_lo[gl_LocalInvocationIndex]);
    atomicMax(g.hi[gl_LocalInvocationIndex], s_hi[gl_LocalInvocationIndex]);
  }
}
