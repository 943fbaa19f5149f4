#version 460
// One separable pass (x or y) of the depth filter; pc.param0 = source
// (0 raw, 1 A, 2 B), param1 = destination (1 A, 2 B), param2 = axis.
//
// Narrow-range filter (Truong & Yuksel 2018), per 1D pass: kernel radius
// 3*sigma_i with sigma_i = H*sigma / (2 z_i tan(fov/2)); neighbours farther
// than z_i + delta_high are ignored together with their mirror (bias
// correction); nearer than z_i - delta_low are clamped to z_i - mu; the
// accepted range widens as pixels are accepted (dynamic range), from the
// centre outwards. The 2D filter is approximated by x then y passes.
// Bilateral Gaussian: spatial Gaussian times a Gaussian of the depth
// difference (sigma_z = delta), background skipped.
#include "common.glsl"
#include "images.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

void main() {
  eye = gl_GlobalInvocationID.z;
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, imageSize(depth_a).xy))) return;
  uint src = pc.param0, dst = pc.param1;
  ivec2 axis = pc.param2 == 0u ? ivec2(1, 0) : ivec2(0, 1);
  float zi = load_depth(src, p);
  if (zi <= 0.0) { store_depth(dst, p, 0.0); return; }

  float sigma_px = g.viewport.y * g.filter_params.x / (2.0 * zi * g.proj.z);
  int radius = min(int(ceil(3.0 * sigma_px)), int(g.filter_params.y));
  if (radius < 1) { store_depth(dst, p, zi); return; }
  float inv2s2 = 1.0 / (2.0 * sigma_px * sigma_px);
  float delta = g.filter_params.z, mu = g.filter_params.w;
  float sum = zi, wsum = 1.0;

  if (g.filter_modes.x == 1u) {
    float d_low = delta, d_high = delta;
    for (int k = 1; k <= radius; ++k) {
      float za = load_depth(src, p + k * axis);
      float zb = load_depth(src, p - k * axis);
      if (za <= 0.0) za = 3.0e38;  // background counts as far
      if (zb <= 0.0) zb = 3.0e38;
      if (za > zi + d_high || zb > zi + d_high) continue;  // bias correction: drop the pair
      float w = exp(-float(k * k) * inv2s2);
      float fa = za, fb = zb;
      if (za >= zi - d_low) {
        d_low = max(d_low, zi - za + delta);
        d_high = max(d_high, za - zi + delta);
      } else {
        fa = zi - mu;
      }
      if (zb >= zi - d_low) {
        d_low = max(d_low, zi - zb + delta);
        d_high = max(d_high, zb - zi + delta);
      } else {
        fb = zi - mu;
      }
      sum += w * (fa + fb);
      wsum += 2.0 * w;
    }
  } else {
    float inv2d2 = 1.0 / (2.0 * delta * delta);
    for (int k = -radius; k <= radius; ++k) {
      if (k == 0) continue;
      float z = load_depth(src, p + k * axis);
      if (z <= 0.0) continue;
      float dz = z - zi;
      float w = exp(-float(k * k) * inv2s2 - dz * dz * inv2d2);
      sum += w * z;
      wsum += w;
    }
  }
  store_depth(dst, p, sum / wsum);
}
