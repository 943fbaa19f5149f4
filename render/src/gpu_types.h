// Internal: host mirrors of the shader-side layouts in shaders/common.glsl.
// Only vec4/mat4-sized members, so std140 and C++ agree without padding.
#pragma once

#include <cstdint>

#include "sluice/render/math.h"

namespace sluice::render {

struct Globals {
  Mat4 view, inv_view;
  float planes[5][4];
  float eye[4];
  float viewport[4];
  float thick_viewport[4];
  float proj[4];
  float radius[4];
  float lod[4];
  uint32_t modes[4];
  float color[4];
  float filter_params[4];
  uint32_t filter_modes[4];
  float shade[4];
  float attenuation[4];
  float opaque_color[4];
  uint32_t display[4];
  float up[4];
  float light[4];
  float scene[4];
  float splat[4];
  float frustum[4];
  float ray[4], thick_ray[4];
  uint32_t stereo[4];  // x: eyes drawn in one pass; y: the host's scene colour given; z: it holds display values
};
static_assert(sizeof(Globals) == 2 * 64 + 27 * 16);

struct PushConstants {
  uint64_t particles = 0, chunks = 0, attributes = 0, blocks = 0, draws = 0, args = 0, big = 0, surface = 0, shapes = 0;
  uint32_t chunk_count = 0, param0 = 0, param1 = 0, param2 = 0;
  uint64_t host_depth = 0;  // the shading pass's copy of the host's depth (passes.cpp, shade)
};
static_assert(sizeof(PushConstants) == 96);

// Args in common.glsl.
struct GpuArgs {
  uint32_t vertex_count, instance_count, first_vertex, first_instance;
  uint32_t groups_x, groups_y, groups_z, block_count;
  uint32_t visible_chunks, splat_x, splat_y, splat_z;
  uint32_t big_count, big_x, big_y, big_z;
};
static_assert(sizeof(GpuArgs) == 64);

}  // namespace sluice::render
