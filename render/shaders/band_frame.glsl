// Shared by band_gather.comp and band_apply.comp: the narrow band of a frame
// that arrived without layers, between the renderer's buffers
// (frame_layout.glsl) and the classifier's (band.glsl). Host side: src/frame_band.cpp.
#include "frame_layout.glsl"

layout(local_size_x = 256) in;

// What band_apply writes: blobs after the particles, the blobs' row count.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer ParticlesOut8 { uvec2 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer ParticlesOut16 { uvec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer ChunksOut { Chunk c[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Floats { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Vec4s { vec4 v[]; };
// band.glsl's Params: the words this side reads.
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Params {
  uint lo[3];
  uint fits;
  uint hi[3];
  uint voxels;
  float origin[3];
  uint cursor;
  float last_cell[3];
  uint blobs;
};

layout(push_constant) uniform Push {
  uvec2 particles;   // the frame's particle buffer (room for `room` blobs after the n particles)
  uvec2 chunks;      // its chunk table; row chunk_count is the blobs' (the host wrote all but its count)
  uvec2 attributes;  // its colour attribute (16-bit), or 0
  uvec2 xyz;         // Floats[3n]: positions for the classifier
  uvec2 attr;        // Floats[n]: the colour attribute's values, or 0
  uvec2 params;      // the classifier's Params
  uvec2 layers;      // Words[n]: the classifier's LAYER region
  uvec2 blobs;       // Vec4s: centroid, count bits
  uvec2 blob_attr;   // Floats: blob mean attribute
  uvec2 surface;     // Words: [0] 1 when valid, then one bit per particle (1: surface)
  uvec2 marks;       // band_gather: Words, a bit per entry, 1: a blob chunk's (zeroed before); or 0
  uint n;
  uint chunk_count;
  uint room;         // blobs that fit after the particles
  uint float_positions;
  uint step;         // band_apply: 0 surface bits, 1 blobs
} pc;

uint workgroup_index() { return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x; }
