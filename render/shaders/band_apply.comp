#version 460
// Narrow band of a frame without layers, step 2, after the classifier:
// step 0 packs every particle's surface bit; step 1 writes the blobs after
// the particles, in the frame's position coding, with their mean colour
// attribute, and their count into the blobs' chunk row. Classification
// that failed (a grid too large) or blobs beyond the room leave the frame
// whole: surface word 0 stays 0 and the blob row empty.
#include "band_frame.glsl"

uint quantize(float v, float lo, float hi) {
  return hi > lo ? uint(clamp(round((v - lo) / (hi - lo) * 65535.0), 0.0, 65535.0)) : 0u;
}

void main() {
  uint index = workgroup_index() * 256u + gl_LocalInvocationIndex;
  Params g = Params(pc.params);
  if (pc.step == 0u) {
    // One word of 32 particles per invocation.
    if (index * 32u >= pc.n) return;
    uint bits = 0u;
    for (uint b = 0u; b < 32u; ++b) {
      uint i = index * 32u + b;
      if (i < pc.n && Words(pc.layers).v[i] != 0u) bits |= 1u << b;
    }
    Words(pc.surface).v[1u + index] = bits;
    return;
  }
  bool valid = g.fits != 0u && g.blobs <= pc.room;
  if (index == 0u) {
    Words(pc.surface).v[0] = valid ? 1u : 0u;
    ChunksOut(pc.chunks).c[pc.chunk_count].count = valid ? g.blobs : 0u;
  }
  if (!valid || index >= g.blobs) return;
  Chunk c = Chunks(pc.chunks).c[pc.chunk_count];
  vec4 blob = Vec4s(pc.blobs).v[index];
  uint count = min(floatBitsToUint(blob.w), 65535u);  // the LOD value's 16 bits
  uint i = pc.n + index;
  if (pc.float_positions == 0u) {
    uvec3 q = uvec3(quantize(blob.x, c.lo.x, c.hi.x), quantize(blob.y, c.lo.y, c.hi.y), quantize(blob.z, c.lo.z, c.hi.z));
    ParticlesOut8(pc.particles).v[i] = uvec2(q.x | (q.y << 16), q.z | (count << 16));
  } else {
    ParticlesOut16(pc.particles).v[i] = uvec4(floatBitsToUint(blob.xyz), count);
  }
  if (pc.attributes != uvec2(0u)) {
    // Two values share a word, and a blob's may share the last particle's.
    uint q = quantize(Floats(pc.blob_attr).v[index], c.attr_range.x, c.attr_range.y);
    uint shift = (i & 1u) * 16u;
    atomicAnd(Words(pc.attributes).v[i >> 1], ~(0xffffu << shift));
    atomicOr(Words(pc.attributes).v[i >> 1], q << shift);
  }
}
