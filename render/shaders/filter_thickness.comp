#version 460
// One separable Gaussian pass over the thickness and volume-colour buffer;
// parameters as in filter_depth.comp. Radius in pixels of this buffer.
#include "common.glsl"
#include "images.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

void main() {
  eye = gl_GlobalInvocationID.z;
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, imageSize(thick_a).xy))) return;
  uint src = pc.param0, dst = pc.param1;
  ivec2 axis = pc.param2 == 0u ? ivec2(1, 0) : ivec2(0, 1);
  int radius = int(g.filter_modes.z);
  float sigma = max(float(radius) / 2.0, 0.5);
  float inv2s2 = 1.0 / (2.0 * sigma * sigma);
  vec2 sum = load_thickness(src, p);
  float wsum = 1.0;
  for (int k = 1; k <= radius; ++k) {
    float w = exp(-float(k * k) * inv2s2);
    sum += w * (load_thickness(src, p + k * axis) + load_thickness(src, p - k * axis));
    wsum += 2.0 * w;
  }
  store_thickness(dst, p, sum / wsum);
}
