#version 460
// Narrow band of a frame without layers, step 1: the frame's particles as
// float positions (and colour attribute values) for the classifier. One
// workgroup per chunk, decoding as every pass of a view does. For the
// ellipsoids of a frame with blob chunks: their entries marked, so that
// band_ellipsoids leaves them out.
#include "band_frame.glsl"

void main() {
  uint c_index = workgroup_index();
  if (c_index >= pc.chunk_count) return;
  Chunk c = Chunks(pc.chunks).c[c_index];
  for (uint k = gl_LocalInvocationIndex; k < c.count; k += 256u) {
    uint i = c.first + k;
    vec3 pos;
    uint lod_value;
    decode_position(pc.particles, pc.float_positions != 0u, c, i, pos, lod_value);
    Floats xyz = Floats(pc.xyz);
    xyz.v[3u * i] = pos.x;
    xyz.v[3u * i + 1u] = pos.y;
    xyz.v[3u * i + 2u] = pos.z;
    if (pc.attributes != uvec2(0u)) Floats(pc.attr).v[i] = attribute_value(pc.attributes, c, i);
    if (c.kind == 1u && pc.marks != uvec2(0u)) atomicOr(Words(pc.marks).v[i >> 5], 1u << (i & 31u));
  }
}
