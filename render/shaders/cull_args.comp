#version 460
// Turns a count the previous pass produced into a dispatch size (2D: x at
// most 65535, the minimum maxComputeWorkGroupCount). pc.param0 picks which:
// 0 blocks -> particle cull (4 blocks per group), 1 draw list -> small splats (64 per group),
// 2 large splats -> one group each.
#include "common.glsl"

layout(local_size_x = 1) in;

uvec3 groups_for(uint n) {
  uint x = min(n, 65535u);
  return uvec3(x, x == 0u ? 0u : (n + x - 1u) / x, 1u);
}

void main() {
  Args args = Args(pc.args);
  if (pc.param0 == 0u) {
    uvec3 d = groups_for((args.block_count + 3u) / 4u);  // cull_particles.comp: 4 blocks per workgroup
    args.groups_x = d.x;
    args.groups_y = d.y;
    args.groups_z = d.z;
  } else if (pc.param0 == 1u) {
    uvec3 d = groups_for((args.vertex_count + 63u) / 64u);
    args.splat_x = d.x;
    args.splat_y = d.y;
    args.splat_z = d.z;
  } else {
    uvec3 d = groups_for(args.big_count);
    args.big_x = d.x;
    args.big_y = d.y;
    args.big_z = d.z;
  }
}
