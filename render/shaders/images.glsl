// The screen-space targets (descriptor set 0, after the uniforms). Raw
// buffers are what the sphere passes rasterize; filters ping-pong through
// B into A, so the filtered result always ends in A and raw stays intact.
layout(set = 0, binding = 1, r32f) uniform image2D depth_raw;
layout(set = 0, binding = 2, r32f) uniform image2D depth_a;
layout(set = 0, binding = 3, r32f) uniform image2D depth_b;
layout(set = 0, binding = 4, rg32f) uniform image2D thick_raw;
layout(set = 0, binding = 5, rg32f) uniform image2D thick_a;
layout(set = 0, binding = 6, rg32f) uniform image2D thick_b;
layout(set = 0, binding = 7) uniform sampler2D thick_raw_tex;
layout(set = 0, binding = 8) uniform sampler2D thick_a_tex;
// The shaded output: sluice's own RGBA8 image, or the caller's colour image
// when the target allows storage (any 4-channel format: written without a
// format qualifier, shaderStorageImageWriteWithoutFormat).
layout(set = 0, binding = 9) uniform writeonly image2D out_color;
layout(set = 0, binding = 10, rgba32f) uniform writeonly image2D out_aux;
// Compute splatting: depth as the bits of a positive float (ordered like
// uints, so atomicMin keeps the nearest), thickness as fixed point sums.
layout(set = 0, binding = 11, r32ui) uniform uimage2D depth_u;
layout(set = 0, binding = 12, r32ui) uniform uimage2D thick_u;
layout(set = 0, binding = 13, r32ui) uniform uimage2D thick_attr_u;

// 0 raw, 1 A, 2 B; out of the image reads as 0 (no fluid).
float load_depth(uint which, ivec2 p) {
  if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, imageSize(depth_a)))) return 0.0;
  if (which == 0u) return imageLoad(depth_raw, p).x;
  if (which == 1u) return imageLoad(depth_a, p).x;
  return imageLoad(depth_b, p).x;
}
void store_depth(uint which, ivec2 p, float z) {
  if (which == 1u) imageStore(depth_a, p, vec4(z));
  else imageStore(depth_b, p, vec4(z));
}
vec2 load_thickness(uint which, ivec2 p) {
  p = clamp(p, ivec2(0), imageSize(thick_a) - 1);
  if (which == 0u) return imageLoad(thick_raw, p).xy;
  if (which == 1u) return imageLoad(thick_a, p).xy;
  return imageLoad(thick_b, p).xy;
}
void store_thickness(uint which, ivec2 p, vec2 t) {
  if (which == 1u) imageStore(thick_a, p, vec4(t, 0.0, 0.0));
  else imageStore(thick_b, p, vec4(t, 0.0, 0.0));
}
