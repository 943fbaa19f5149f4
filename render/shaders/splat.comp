#version 460
// Sphere impostors without the rasterizer: every kept particle's pixels get
// the exact ray-sphere depth (atomicMin on the float's bits) and the chord
// through it (fixed-point atomicAdd, with the colour attribute weighted in)
// at the thickness buffer's resolution. pc.param0 = 0: one thread per draw
// item; items with more than g.splat.z pixels to visit (depth and thickness
// together) are listed for param0 = 1: one workgroup per listed item. Both
// eyes of a 2-layer target splat the same draw list: one small-splat
// dispatch per eye (pc.param1), in turn, so only one eye's targets are hit
// by atomics at a time (both eyes' at once took twice as long on the H200 at
// 2064x2208, likely outgrowing its L2); large items carry their eye in the
// top bit. GPUs with few raster units (H100) run this far faster than point
// sprites, and integer atomics make the sums independent of order
// (deterministic images).
#include "common.glsl"
#include "images.glsl"

layout(local_size_x = 64) in;

struct Sphere {
  vec3 c;   // eye space
  float r;  // blobs: the splat's reach
  float attr;
  float count;  // blobs: particles; 0: a sphere
  float sigma;  // blobs
  bool ellipsoid;  // anisotropic particles: q and b describe it, r does not
  mat3 q;          // its eye-space quadric (eye_quadric) and q^-1
  mat3 b;
};

Sphere load(uint item) {
  DrawItem it = load_item(item);
  Sphere s;
  s.c = (g.view * vec4(it.pos, 1.0)).xyz;
  s.r = it.radius;
  s.attr = it.attr;
  s.count = it.count;
  s.sigma = it.sigma;
  s.ellipsoid = it.ellipsoid;
  s.q = s.ellipsoid ? eye_quadric(it) : mat3(1.0);
  s.b = s.ellipsoid ? inverse(s.q) : mat3(1.0);
  return s;
}

// Pixels [lo, hi) whose centres can fall inside the sphere's projection.
void pixel_box(Sphere s, vec4 vp, out ivec2 lo, out ivec2 hi) {
  vec2 a, b;
  if (s.ellipsoid) {
    ellipsoid_bounds(s.c, s.q, vp, a, b);
  } else {
    sphere_bounds(s.c, s.r, vp, a, b);
  }
  lo = clamp(ivec2(floor(a)), ivec2(0), ivec2(vp.xy));
  hi = clamp(ivec2(ceil(b)), ivec2(0), ivec2(vp.xy));
}

// The pixel's ray against the particle: false on a miss; else the hit's
// depth and the thickness the particle adds along the ray (world): the
// chord through a sphere or ellipsoid, a blob's Gaussian.
bool ray_hit(Sphere s, ivec2 p, vec4 k, out float z, out float thickness) {
  vec3 dir = eye_ray(vec2(p) + 0.5, k);
  float inv_len = inversesqrt(dot(dir, dir));
  vec3 n = dir * inv_len;
  if (s.ellipsoid) {
    float near;
    bool hit = ray_ellipsoid(s.c, s.b, n, near, thickness);
    z = near * inv_len;  // dir.z = -1: distance along the ray * |n.z|
    return hit;
  }
  float tc = dot(n, s.c);
  vec3 perp = s.c - tc * n;
  float h2 = s.r * s.r - dot(perp, perp);
  z = (tc - sqrt(max(h2, 0.0))) * inv_len;
  if (h2 < 0.0) return false;
  // (For a blob, r^2 - h2 is the ray's squared distance from its centroid.)
  thickness = s.count > 0.0 ? blob_thickness(s.count, s.sigma, s.r * s.r - h2) : 2.0 * sqrt(h2);
  return true;
}

void depth_pixel(Sphere s, ivec2 p) {
  float z, thickness;
  if (!ray_hit(s, p, g.ray, z, thickness)) return;
  uint bits = floatBitsToUint(z);
  ivec3 q = ivec3(p, eye);
  if (imageLoad(depth_u, q).x > bits) imageAtomicMin(depth_u, q, bits);
}

void thickness_pixel(Sphere s, ivec2 p, bool attr) {
  float z, thickness;
  if (!ray_hit(s, p, g.thick_ray, z, thickness)) return;
  float fixed_point = thickness * g.splat.x;
  uint t = uint(fixed_point + 0.5);
  if (t == 0u) return;
  imageAtomicAdd(thick_u, ivec3(p, eye), t);
  if (attr) imageAtomicAdd(thick_attr_u, ivec3(p, eye), uint(fixed_point * s.attr + 0.5));
}

void main() {
  bool attr = views[0].modes.w != 0u;
  if (pc.param0 == 0u) {
    eye = pc.param1;  // one dispatch per eye over the whole draw list
    uint item = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
    Args args = Args(pc.args);
    if (item >= args.vertex_count) return;
    Sphere s = load(item);
    ivec2 lo, hi, tlo, thi;
    pixel_box(s, g.viewport, lo, hi);
    pixel_box(s, g.thick_viewport, tlo, thi);
    // The pixels this thread would visit: depth at full resolution (not
    // for blobs, which add thickness only), thickness at its own.
    vec2 size = vec2(max(hi - lo, ivec2(0))), tsize = vec2(max(thi - tlo, ivec2(0)));
    if ((s.count == 0.0 ? size.x * size.y : 0.0) + tsize.x * tsize.y > g.splat.z) {
      Items(pc.big).i[atomicAdd(args.big_count, 1u)] = item | (eye << 31);  // large in this eye
      return;
    }
    if (s.count == 0.0) {  // blobs add thickness only
      for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x) depth_pixel(s, ivec2(x, y));
    }
    for (int y = tlo.y; y < thi.y; ++y)
      for (int x = tlo.x; x < thi.x; ++x) thickness_pixel(s, ivec2(x, y), attr);
  } else {
    uint index = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (index >= Args(pc.args).big_count) return;
    uint listed = Items(pc.big).i[index];
    eye = listed >> 31;
    Sphere s = load(listed & 0x7fffffffu);
    ivec2 lo, hi, tlo, thi;
    pixel_box(s, g.viewport, lo, hi);
    pixel_box(s, g.thick_viewport, tlo, thi);
    ivec2 size = max(hi - lo, ivec2(0));
    uint area = s.count == 0.0 ? uint(size.x) * uint(size.y) : 0u;
    for (uint i = gl_LocalInvocationIndex; i < area; i += 64u) {
      depth_pixel(s, lo + ivec2(int(i % uint(size.x)), int(i / uint(size.x))));
    }
    ivec2 tsize = max(thi - tlo, ivec2(0));
    uint tarea = uint(tsize.x) * uint(tsize.y);
    for (uint i = gl_LocalInvocationIndex; i < tarea; i += 64u) {
      thickness_pixel(s, tlo + ivec2(int(i % uint(tsize.x)), int(i / uint(tsize.x))), attr);
    }
  }
}
