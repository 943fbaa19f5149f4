#version 460
// Narrow band of a frame without layers, step 1: the frame's particles as
// float positions (and colour attribute values) for the classifier. One
// workgroup per chunk; the decoding is common.glsl's decode_particle.
#include "band_frame.glsl"

void main() {
  uint c_index = workgroup_index();
  if (c_index >= pc.chunk_count) return;
  Chunk c = Chunks(pc.chunks).c[c_index];
  vec3 scale = (c.hi - c.lo) * (1.0 / 65535.0);
  for (uint k = gl_LocalInvocationIndex; k < c.count; k += 256u) {
    uint i = c.first + k;
    vec3 pos;
    if (pc.float_positions == 0u) {
      uvec2 raw = Particles8(pc.particles).v[i];
      pos = c.lo + vec3(uvec3(raw.x & 0xffffu, raw.x >> 16, raw.y & 0xffffu)) * scale;
    } else {
      pos = uintBitsToFloat(Particles16(pc.particles).v[i].xyz);
    }
    Floats xyz = Floats(pc.xyz);
    xyz.v[3u * i] = pos.x;
    xyz.v[3u * i + 1u] = pos.y;
    xyz.v[3u * i + 2u] = pos.z;
    if (pc.attributes != uvec2(0u)) {
      uint word = Words(pc.attributes).v[i >> 1];
      float q = float((i & 1u) == 0u ? (word & 0xffffu) : (word >> 16));
      Floats(pc.attr).v[i] = c.attr_range.x + q * ((c.attr_range.y - c.attr_range.x) * (1.0 / 65535.0));
    }
  }
}
