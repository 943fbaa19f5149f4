#version 460
// Per particle: dequantize, frustum and near-camera culling (thesis 3.4),
// continuous LOD (thesis 3.1, see include/sluice/render/lod.h), and
// compaction of the survivors into the draw list and the indirect draw.
#extension GL_KHR_shader_subgroup_ballot : require
#include "common.glsl"

layout(local_size_x = 256) in;
const uint kBlocksPerGroup = 4u;  // cull_args.comp sizes the dispatch by it

shared uint s_count;
shared uint s_base;

// Thesis formula 3.2.
float position_hash(vec3 p) {
  return fract(sin(dot(p, vec3(12.9898, 78.233, 54.143))) * 437586.5453);
}

// A blob's random term, 0..1: an integer hash of the world cell of side
// `voxel` its centroid lies in. io::blob_lod_uniform() computes the same on
// the host: files tier their blobs by it (format 1.4), so the two must agree.
float cell_hash(vec3 p, float voxel) {
  ivec3 c = ivec3(floor(p / voxel));
  uint h = uint(c.x) * 73856093u ^ uint(c.y) * 19349663u ^ uint(c.z) * 83492791u;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return (float(h >> 8) + 0.5) * (1.0 / 16777216.0);
}

// Whether this invocation's particle of block `block_index` is drawn, and
// its draw entry's second word.
bool consider(uint block_index, out uint packed) {
  packed = 0u;
  uvec2 block = Blocks(pc.blocks).b[block_index];
  bool inside = (block.y & 0x80000000u) != 0u;  // the chunk pass proved the tests below pass
  Chunk c = Chunks(pc.chunks).c[block.x];
  uint local = (block.y & 0x7fffffffu) + gl_LocalInvocationIndex;
  bool keep = local < c.count;
  uint index = c.first + min(local, c.count - 1u);

  // Inside every eye's frustum with LOD off, nothing about a particle's
  // position decides: it is not read.
  vec3 pos = vec3(0.0);
  uint lod_value = 0u;
  if (!inside || views[0].modes.x != 0u) decode_particle(c, index, pos, lod_value);
  bool blob = c.kind == 1u;

  // A frame classified on the GPU: its interior particles are not drawn
  // (its blobs, a chunk of their own, stand for them).
  if (keep && !blob && pc.surface != uvec2(0u)) {
    Surface s = Surface(pc.surface);
    if (s.w[0] != 0u && ((s.w[1u + (index >> 5)] >> (index & 31u)) & 1u) == 0u) keep = false;
  }

  // One decision for every eye (a particle kept for one eye and not the
  // other would shimmer between them): the LOD importance is the largest
  // any eye gives it; it is kept when some eye's frustum holds it and no eye
  // has it too near or too large.
  float r0 = blob ? kBlobReach * blob_sigma(c.voxel, views[0].radius.x) : views[0].radius.x;
  float scale = 1.0;
  if (views[0].modes.x != 0u && keep) {
    // Importance w (formula 3.1 with CLOD = 1000 / d_ref) and random term.
    float w = 0.0;
    for (eye = 0u; eye < views[0].stereo.x; ++eye) {
      vec3 e = (g.view * vec4(pos, 1.0)).xyz;
      vec2 ndc = vec2(g.proj.x * e.x, -g.proj.y * e.y) / max(-e.z, 1e-20) + g.frustum.xy;
      float centre = max(1.0 - 0.7 * min(length(ndc) * 0.70710678, 1.0), 0.3);
      w = max(w, centre / (max(length(e), 1e-20) * g.lod.z));
    }
    eye = 0u;
    // Blobs thin out with LOD like particles; their random term hashes the
    // world cell of their voxel (their LOD value is a count, and the cell
    // stays while the voxel is occupied), and in density-preserving LOD a
    // kept blob stands for scale^3 times its particles (a grown particle's
    // volume), so the expected thickness stays.
    float u = blob ? cell_hash(pos, c.voxel) : g.modes.y == 0u ? (float(lod_value) + 0.5) * (1.0 / 65536.0) : position_hash(pos);
    float lod = w * -log(1.0 - u);
    keep = lod >= g.lod.y;
    if (g.modes.x == 2u) {
      // Density preserving: grow by (1/p)^(1/3), p = level^(1/w).
      scale = min(exp(g.lod.y / (3.0 * w)), g.lod.w);
    }
  }
  float r = blob ? r0 : r0 * scale;
  // Anisotropic particles reach up to their longest axis from their shifted centre.
  float reach = blob || pc.shapes == uvec2(0u) ? r : r * kLongestAxis + largest_shift();
  if (keep && !inside) {
    // In some eye's frustum, and not too near or too large in any.
    bool seen = false, fits = true;
    for (eye = 0u; eye < views[0].stereo.x; ++eye) {
      bool in_eye = true;
      for (int i = 0; i < 5; ++i) {
        if (dot(g.planes[i].xyz, pos) + g.planes[i].w < -reach) in_eye = false;
      }
      seen = seen || in_eye;
      // Near-camera culling: too close, or a splat too large for the filter.
      // A blob goes when its particles would (its splat is wide by design).
      float dist = -(g.view * vec4(pos, 1.0)).z;  // along the view axis
      // (An ellipsoid's whole reach stays off the near plane; its size is its sphere's.)
      float rn = blob ? g.radius.x : r;
      if (dist - (blob ? rn : reach) < max(g.eye.w, g.radius.w)) fits = false;
      if (2.0 * rn * g.proj.y * g.viewport.y * 0.5 > g.radius.z * max(dist - rn, 1e-20)) fits = false;
    }
    eye = 0u;
    keep = seen && fits;
  }

  float t = 0.0;
  if (keep && g.modes.w != 0u) {
    float value = attribute_value(pc.attributes, c, index);
    t = clamp((value - g.color.x) * g.color.y, 0.0, 1.0);
  }

  if (keep) {
    uint growth = g.lod.w > 1.0 ? uint((scale - 1.0) / (g.lod.w - 1.0) * 4095.0 + 0.5) : 0u;
    packed = gl_LocalInvocationIndex | (min(growth, 4095u) << 8) | (uint(t * 4095.0 + 0.5) << 20);
  }
  return keep;
}

// kBlocksPerGroup blocks per workgroup, one particle of each per
// invocation: one atomic on the draw list's counter per workgroup (at one a
// block, 100M particles made 390k of them on one address).
void main() {
  Args args = Args(pc.args);
  uint first_block = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kBlocksPerGroup;
  if (first_block >= args.block_count) return;  // whole workgroup: uniform
  if (gl_LocalInvocationIndex == 0u) s_count = 0u;
  barrier();
  bool keep[kBlocksPerGroup];
  uint slot[kBlocksPerGroup], packed[kBlocksPerGroup];
  for (uint k = 0u; k < kBlocksPerGroup; ++k) {
    keep[k] = first_block + k < args.block_count && consider(first_block + k, packed[k]);
    // Compaction: a subgroup's kept particles take consecutive slots, one
    // shared atomic per subgroup.
    uvec4 ballot = subgroupBallot(keep[k]);
    uint subgroup_base = 0u;
    if (subgroupElect()) subgroup_base = atomicAdd(s_count, subgroupBallotBitCount(ballot));
    slot[k] = subgroupBroadcastFirst(subgroup_base) + subgroupBallotExclusiveBitCount(ballot);
  }
  barrier();
  if (gl_LocalInvocationIndex == 0u) s_base = s_count == 0u ? 0u : atomicAdd(args.vertex_count, s_count);
  barrier();
  Draws draws = Draws(pc.draws);
  for (uint k = 0u; k < kBlocksPerGroup; ++k) {
    if (keep[k]) draws.d[s_base + slot[k]] = uvec2(first_block + k, packed[k]);
  }
}
