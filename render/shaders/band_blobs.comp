#version 460
// Narrow band, pass 9: one blob per voxel holding interior particles (their
// centroid, count and mean attribute), and every interior particle's blob.
#include "band.glsl"

shared uint s_blobs, s_base;

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u || pc.with_blobs == 0u) return;
  uint voxels = g.voxels;
  for (uint base = first_item(); base < voxels; base += round_stride()) {
    if (gl_LocalInvocationIndex == 0u) s_blobs = 0u;
    barrier();
    uint v = base + gl_LocalInvocationIndex;
    uint s = v < voxels ? VOXEL(v) : kEmpty;
    uint first = 0u, end = 0u, interior = 0u;
    vec3 sum = vec3(0.0);
    float attr_sum = 0.0;
    if (s != kEmpty) {
      end = START(s);
      first = end - COUNT(s);
      for (uint k = first; k < end; ++k) {
        uint j = LIST(k);
        if (LAYER(j) != 0u) continue;
        sum += particle(j);
        if (pc.attr != uvec2(0u)) attr_sum += Floats(pc.attr).v[j];
        ++interior;
      }
    }
    uint index = interior > 0u ? atomicAdd(s_blobs, 1u) : 0u;
    barrier();
    if (gl_LocalInvocationIndex == 0u) s_base = s_blobs > 0u ? atomicAdd(g.blobs, s_blobs) : 0u;
    barrier();
    if (interior > 0u) {
      uint b = s_base + index;
      Vec4s(pc.blobs).v[b] = vec4(sum / float(interior), uintBitsToFloat(interior));
      if (pc.attr != uvec2(0u)) Floats(pc.blob_attr).v[b] = attr_sum / float(interior);
      for (uint k = first; k < end; ++k) {
        uint j = LIST(k);
        if (LAYER(j) == 0u) BLOB_OF(j) = b;
      }
    }
    barrier();
  }
}
