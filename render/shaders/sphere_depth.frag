#version 460
// Exact sphere depth per pixel: ray-sphere intersection in eye space (or
// ray-ellipsoid, for anisotropic particles). Writes
// the hardware depth (reversed z) and the linear depth used by the filters.
#extension GL_EXT_multiview : require
#include "common.glsl"

layout(location = 0) flat in vec3 v_center;
layout(location = 1) flat in float v_radius;
layout(location = 2) flat in float v_attr;
layout(location = 4) flat in uint v_ellipsoid;
layout(location = 5) flat in mat3 v_inverse;
layout(location = 0) out float o_depth;  // distance along the view axis
layout(depth_less) out float gl_FragDepth;

void main() {
  eye = gl_ViewIndex;  // multiview: one layer per eye (0 otherwise)
  vec3 dir = eye_ray(gl_FragCoord.xy, g.ray);
  float inv_len = inversesqrt(dot(dir, dir));
  vec3 n = dir * inv_len;
  if (v_ellipsoid != 0u) {
    float near, chord;
    if (!ray_ellipsoid(v_center, v_inverse, n, near, chord)) discard;
    o_depth = near * inv_len;
    gl_FragDepth = g.eye.w / o_depth;
    return;
  }
  // Closest approach first: stable when the sphere is tiny and far away.
  float tc = dot(n, v_center);
  vec3 perp = v_center - tc * n;
  float h2 = v_radius * v_radius - dot(perp, perp);
  if (h2 < 0.0) discard;
  float z = (tc - sqrt(h2)) * inv_len;  // dir.z = -1: distance along the ray * |n.z|
  o_depth = z;
  gl_FragDepth = g.eye.w / z;
}
