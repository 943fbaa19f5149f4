#version 460
// Narrow band, pass 4: the occupied slots into a list of voxels, and each
// voxel its range of places in the particle lists (workgroup by workgroup:
// one global atomic per 256 slots).
#include "band.glsl"

shared uint s_voxels, s_places, s_voxel_base, s_place_base;

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u) return;
  uint capacity = pc.mask + 1u;
  for (uint base = first_item(); base < capacity; base += round_stride()) {
    if (gl_LocalInvocationIndex == 0u) {
      s_voxels = 0u;
      s_places = 0u;
    }
    barrier();
    uint s = base + gl_LocalInvocationIndex;
    bool occupied = s < capacity && (g.dense != 0u ? COUNT(s) != 0u : KEY(s) != kEmpty);
    uint index = 0u, place = 0u;
    if (occupied) {
      index = atomicAdd(s_voxels, 1u);
      place = atomicAdd(s_places, COUNT(s));
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_voxels > 0u) {
      s_voxel_base = atomicAdd(g.voxels, s_voxels);
      s_place_base = atomicAdd(g.cursor, s_places);
    }
    barrier();
    if (occupied) {
      VOXEL(s_voxel_base + index) = s;
      START(s) = s_place_base + place;
    }
    barrier();
  }
}
