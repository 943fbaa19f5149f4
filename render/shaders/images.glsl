// The screen-space targets (descriptor set 0, after the uniforms), arrays of
// one layer per eye (`eye` picks it). Raw buffers are what the sphere passes
// rasterize; filters ping-pong through B into A, so the filtered result
// always ends in A and raw stays intact.
layout(set = 0, binding = 1, r32f) uniform image2DArray depth_raw;
layout(set = 0, binding = 2, r32f) uniform image2DArray depth_a;
layout(set = 0, binding = 3, r32f) uniform image2DArray depth_b;
layout(set = 0, binding = 4, rg32f) uniform image2DArray thick_raw;
layout(set = 0, binding = 5, rg32f) uniform image2DArray thick_a;
layout(set = 0, binding = 6, rg32f) uniform image2DArray thick_b;
layout(set = 0, binding = 7) uniform sampler2DArray thick_raw_tex;
layout(set = 0, binding = 8) uniform sampler2DArray thick_a_tex;
// The shaded output: sluice's own RGBA8 image, or the caller's colour image
// when the target allows storage (any 4-channel format: written without a
// format qualifier, shaderStorageImageWriteWithoutFormat).
layout(set = 0, binding = 9) uniform writeonly image2DArray out_color;
layout(set = 0, binding = 10, rgba32f) uniform writeonly image2DArray out_aux;
// Compute splatting: depth as the bits of a positive float (ordered like
// uints, so atomicMin keeps the nearest), thickness as fixed point sums.
layout(set = 0, binding = 11, r32ui) uniform uimage2DArray depth_u;
layout(set = 0, binding = 12, r32ui) uniform uimage2DArray thick_u;
layout(set = 0, binding = 13, r32ui) uniform uimage2DArray thick_attr_u;

// 0 raw, 1 A, 2 B; out of the image reads as 0 (no fluid).
float load_depth(uint which, ivec2 p) {
  if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, imageSize(depth_a).xy))) return 0.0;
  ivec3 q = ivec3(p, eye);
  if (which == 0u) return imageLoad(depth_raw, q).x;
  if (which == 1u) return imageLoad(depth_a, q).x;
  return imageLoad(depth_b, q).x;
}
void store_depth(uint which, ivec2 p, float z) {
  if (which == 1u) imageStore(depth_a, ivec3(p, eye), vec4(z));
  else imageStore(depth_b, ivec3(p, eye), vec4(z));
}
vec2 load_thickness(uint which, ivec2 p) {
  ivec3 q = ivec3(clamp(p, ivec2(0), imageSize(thick_a).xy - 1), eye);
  if (which == 0u) return imageLoad(thick_raw, q).xy;
  if (which == 1u) return imageLoad(thick_a, q).xy;
  return imageLoad(thick_b, q).xy;
}
void store_thickness(uint which, ivec2 p, vec2 t) {
  if (which == 1u) imageStore(thick_a, ivec3(p, eye), vec4(t, 0.0, 0.0));
  else imageStore(thick_b, ivec3(p, eye), vec4(t, 0.0, 0.0));
}
