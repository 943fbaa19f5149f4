#version 460
// A unit cube (0..1 on each axis) placed by the push constants: 36 vertices
// from gl_VertexIndex, one normal per face.
layout(push_constant) uniform Push {
  mat4 clip_from_world;
  vec4 lo;     // world corner
  vec4 size;   // world extent
  vec4 color;
} pc;
layout(location = 0) flat out vec3 normal;

const vec3 kNormals[6] = vec3[](vec3(1, 0, 0), vec3(-1, 0, 0), vec3(0, 1, 0), vec3(0, -1, 0), vec3(0, 0, 1), vec3(0, 0, -1));

void main() {
  int face = gl_VertexIndex / 6, corner = gl_VertexIndex % 6;
  vec3 n = kNormals[face];
  // Two triangles over the face: (0,0) (1,0) (1,1) / (0,0) (1,1) (0,1) in the face's own axes.
  const vec2 uv[6] = vec2[](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1), vec2(0, 1));
  vec3 a = abs(n.x) > 0.5 ? vec3(0, 1, 0) : vec3(1, 0, 0);
  vec3 b = cross(n, a);
  vec3 p = 0.5 + 0.5 * n + (uv[corner].x - 0.5) * a + (uv[corner].y - 0.5) * b;
  normal = n;
  gl_Position = pc.clip_from_world * vec4(pc.lo.xyz + p * pc.size.xyz, 1.0);
}
