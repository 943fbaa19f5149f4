#version 460
// One point sprite per kept particle, placed and sized to cover the sphere's
// exact perspective projection (tangent planes per axis), clamped to the
// viewport so the point's centre is always inside the clip volume (points
// whose centre is outside may be discarded whole). The fragment shaders
// intersect the pixel's ray with the sphere, so the sprite only has to cover.
// Anisotropic particles: the same for the ellipsoid (its exact projected
// box, its nearest depth), whose inverse quadric the fragments get.
#extension GL_EXT_multiview : require
#include "common.glsl"

layout(location = 0) flat out vec3 v_center;  // eye space
layout(location = 1) flat out float v_radius;
layout(location = 2) flat out float v_attr;
layout(location = 3) flat out vec2 v_blob;  // blobs: particle count, sigma; (0, 0): a sphere
layout(location = 4) flat out uint v_ellipsoid;  // 1: an anisotropic particle, v_inverse describes it
layout(location = 5) flat out mat3 v_inverse;    // its eye-space quadric's inverse (ray_ellipsoid's b)

void hide() {
  gl_Position = vec4(4.0, 4.0, 0.5, 1.0);
  gl_PointSize = 1.0;
}

void main() {
  eye = gl_ViewIndex;  // multiview: one layer per eye (0 otherwise)
  DrawItem item = load_item(uint(gl_VertexIndex));
  float r = item.radius;
  vec3 c = (g.view * vec4(item.pos, 1.0)).xyz;
  float d = -c.z;
  v_center = c;
  v_radius = r;
  v_attr = item.attr;
  v_blob = vec2(item.count, item.sigma);
  v_ellipsoid = item.ellipsoid ? 1u : 0u;
  mat3 q = item.ellipsoid ? eye_quadric(item) : mat3(1.0);
  v_inverse = item.ellipsoid ? inverse(q) : mat3(1.0);
  float reach = item.ellipsoid ? sqrt(q[2][2]) : r;  // towards the eye
  if (d - reach <= g.eye.w) { hide(); return; }
  if (item.count > 0.0 && pc.param0 == 0u) { hide(); return; }  // blobs add thickness only

  vec4 vp = pc.param0 == 1u ? g.thick_viewport : g.viewport;
  vec2 lo, hi;
  if (item.ellipsoid) {
    ellipsoid_bounds(c, q, vp, lo, hi);
  } else {
    sphere_bounds(c, r, vp, lo, hi);
  }
  lo = clamp(lo, vec2(0.0), vp.xy);
  hi = clamp(hi, vec2(0.0), vp.xy);
  if (any(lessThanEqual(hi, lo))) { hide(); return; }
  vec2 centre = (lo + hi) * 0.5;
  vec2 size = hi - lo;
  gl_PointSize = min(max(size.x, size.y) + 2.0, g.radius.y);
  // Depth of the particle's nearest point: every fragment is at or behind it
  // (reversed z: depth_less in the fragment shader).
  gl_Position = vec4(centre * vp.zw * 2.0 - 1.0, g.eye.w / (d - reach), 1.0);
}
