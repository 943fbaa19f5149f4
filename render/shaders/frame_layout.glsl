// A frame's buffers as the renderer uploads them (src/upload.cpp): the chunk
// table (mirrored by GpuChunk in include/sluice/render/frame.h), particles in
// the scene's position coding, the 16-bit colour attribute. Shared by
// common.glsl (every pass of a view) and band_frame.glsl (classifying a
// frame without layers), so both decode a particle the same way.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

struct Chunk {
  vec3 lo;
  uint first;
  vec3 hi;
  uint count;
  vec2 attr_range;
  uint kind;    // 0: particles; 1: voxel blobs (the LOD value holds the particle count)
  float voxel;  // blobs: side of their voxels (world)
  uint lod_range;  // the LOD values' bounds: lowest | highest << 16 (GpuChunk::lod_lo, lod_hi)
  uint reserved0, reserved1, reserved2;
};

layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer Particles8 { uvec2 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Particles16 { uvec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Chunks { Chunk c[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Attributes { uint v[]; };

// World position and stable LOD value of particle `index` of chunk `c`:
// 16-bit positions quantized over the chunk's box with the LOD value in the
// last 16 bits, or float positions with it in w.
void decode_position(uvec2 particles, bool float_positions, Chunk c, uint index, out vec3 pos, out uint lod_value) {
  if (!float_positions) {
    uvec2 raw = Particles8(particles).v[index];
    uvec3 q = uvec3(raw.x & 0xffffu, raw.x >> 16, raw.y & 0xffffu);
    pos = c.lo + vec3(q) * ((c.hi - c.lo) * (1.0 / 65535.0));
    lod_value = raw.y >> 16;
  } else {
    uvec4 raw = Particles16(particles).v[index];
    pos = uintBitsToFloat(raw.xyz);
    lod_value = raw.w & 0xffffu;
  }
}

// The colour attribute of particle `index` of chunk `c` (world units).
float attribute_value(uvec2 attributes, Chunk c, uint index) {
  uint word = Attributes(attributes).v[index >> 1];
  float q = float((index & 1u) == 0u ? (word & 0xffffu) : (word >> 16));
  return c.attr_range.x + q * ((c.attr_range.y - c.attr_range.x) * (1.0 / 65535.0));
}
