#version 460
// Narrow band, pass 9: one blob per voxel holding interior particles (their
// centroid and count), and every interior particle's blob.
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
    uint s = v < voxels ? Uints(pc.voxels).v[v] : kEmpty;
    uint first = 0u, end = 0u, interior = 0u;
    vec3 sum = vec3(0.0);
    if (s != kEmpty) {
      end = Uints(pc.starts).v[s];
      first = end - Uints(pc.counts).v[s];
      for (uint k = first; k < end; ++k) {
        uint j = Uints(pc.lists).v[k];
        if (Uints(pc.layers).v[j] != 0u) continue;
        sum += particle(j);
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
      for (uint k = first; k < end; ++k) {
        uint j = Uints(pc.lists).v[k];
        if (Uints(pc.layers).v[j] == 0u) Uints(pc.blob_of).v[j] = b;
      }
    }
    barrier();
  }
}
