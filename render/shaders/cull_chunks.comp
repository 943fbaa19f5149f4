#version 460
// Chunk frustum test: one thread per chunk, against every eye's frustum. A visible chunk appends its
// 256-particle blocks to the block list that the particle pass walks, so
// culled chunks cost nothing further.
#include "common.glsl"

layout(local_size_x = 64) in;

// Largest distance any particle's sphere or ellipsoid (or blob's splat) reaches beyond its centre.
float reach(Chunk c) {
  if (c.kind == 1u) return kBlobReach * blob_sigma(c.voxel, g.radius.x);
  float r = pc.shapes != uvec2(0u) ? g.radius.x * kLongestAxis : g.radius.x;
  return (g.modes.x == 2u ? r * g.lod.w : r) + largest_shift();
}

bool aabb_visible(vec3 lo, vec3 hi, float r) {
  for (int i = 0; i < 5; ++i) {
    vec4 p = g.planes[i];
    // The box corner farthest along the plane normal.
    vec3 c = vec3(p.x >= 0.0 ? hi.x : lo.x, p.y >= 0.0 ? hi.y : lo.y, p.z >= 0.0 ? hi.z : lo.z);
    if (dot(p.xyz, c) + p.w < -r) return false;
  }
  return true;
}

// True when no particle of the chunk can fail the per-particle frustum,
// near-plane or splat-size tests: the particle pass then skips them.
bool aabb_inside(vec3 lo, vec3 hi, float r) {
  for (int i = 0; i < 5; ++i) {
    vec4 p = g.planes[i];
    vec3 c = vec3(p.x >= 0.0 ? lo.x : hi.x, p.y >= 0.0 ? lo.y : hi.y, p.z >= 0.0 ? lo.z : hi.z);
    if (dot(p.xyz, c) + p.w < r) return false;
  }
  // Nearest depth along the view axis of any point of the box.
  vec3 row = vec3(g.view[0][2], g.view[1][2], g.view[2][2]);
  vec3 centre = 0.5 * (lo + hi), half_size = 0.5 * (hi - lo);
  float nearest = -(dot(row, centre) + g.view[3][2] + dot(abs(row), half_size));
  if (nearest - r < max(g.eye.w, g.radius.w)) return false;
  return r * g.proj.y * g.viewport.y <= g.radius.z * (nearest - r);
}

// Whether the LOD test (cull_particles.comp) can keep any particle of the
// chunk: its largest LOD value (GpuChunk::lod_hi) at the largest importance
// any eye gives a point of its box (the centre weight at most 1, the
// nearest distance). A file's tiers make most of a far cell's records fail
// here: they are dropped without reading a particle.
bool lod_may_keep(Chunk c) {
  if (views[0].modes.x == 0u || views[0].modes.y != 0u) return true;  // LOD off, or random terms from positions
  uint highest = c.lod_range >> 16;
  if (highest >= 65535u) return true;
  float u = float(highest + 1u) * (1.0 / 65536.0);  // above any value's (v + 0.5) / 65536, and a blob's bound
  float w = 0.0;
  for (eye = 0u; eye < views[0].stereo.x; ++eye) {
    vec3 outside = max(max(c.lo - g.eye.xyz, g.eye.xyz - c.hi), vec3(0.0));
    w = max(w, 1.0 / (max(length(outside), 1e-20) * g.lod.z));
  }
  eye = 0u;
  return w * -log(1.0 - u) >= g.lod.y * (1.0 - 1e-3);  // (a margin for the particle pass's rounding)
}

void main() {
  uint i = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * 64u) + gl_GlobalInvocationID.x;
  if (i >= pc.chunk_count) return;
  Chunk c = Chunks(pc.chunks).c[i];
  if (c.count == 0u) return;
  // One cull for every eye: visible to any, "inside" only when inside all.
  bool visible = false, inside_all = true;
  for (eye = 0u; eye < views[0].stereo.x; ++eye) {
    float r = reach(c);
    visible = visible || aabb_visible(c.lo, c.hi, r);
    inside_all = inside_all && aabb_inside(c.lo, c.hi, r);
  }
  if (!visible || !lod_may_keep(c)) return;
  Args args = Args(pc.args);
  atomicAdd(args.visible_chunks, 1u);
  uint blocks = (c.count + kBlock - 1u) / kBlock;
  uint base = atomicAdd(args.block_count, blocks);
  uint inside = inside_all ? 0x80000000u : 0u;
  Blocks list = Blocks(pc.blocks);
  for (uint b = 0u; b < blocks; ++b) list.b[base + b] = uvec2(i, (b * kBlock) | inside);
}
