#version 460
// Additive thickness: the chord of the pixel's ray through the sphere (or
// the ellipsoid, for anisotropic particles), and
// the chord weighted by the colour attribute (for volume colour).
#extension GL_EXT_multiview : require
#include "common.glsl"

layout(location = 0) flat in vec3 v_center;
layout(location = 1) flat in float v_radius;
layout(location = 2) flat in float v_attr;
layout(location = 3) flat in vec2 v_blob;
layout(location = 4) flat in uint v_ellipsoid;
layout(location = 5) flat in mat3 v_inverse;
layout(location = 0) out vec2 o_thickness;

void main() {
  eye = gl_ViewIndex;  // multiview: one layer per eye (0 otherwise)
  vec3 n = normalize(eye_ray(gl_FragCoord.xy, g.thick_ray));
  if (v_ellipsoid != 0u) {
    float near, chord;
    if (!ray_ellipsoid(v_center, v_inverse, n, near, chord)) discard;
    o_thickness = vec2(chord, chord * v_attr);
    return;
  }
  float tc = dot(n, v_center);
  vec3 perp = v_center - tc * n;
  float h2 = v_radius * v_radius - dot(perp, perp);
  if (h2 < 0.0) discard;
  float chord = 2.0 * sqrt(h2);
  if (v_blob.x > 0.0) chord = blob_thickness(v_blob.x, v_blob.y, v_radius * v_radius - h2);  // h2 = reach^2 - distance^2
  o_thickness = vec2(chord, chord * v_attr);
}
