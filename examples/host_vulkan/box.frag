#version 460
layout(push_constant) uniform Push {
  mat4 clip_from_world;
  vec4 lo;
  vec4 size;
  vec4 color;
} pc;
layout(location = 0) flat in vec3 normal;
layout(location = 0) out vec4 frag;

void main() {
  float light = 0.35 + 0.65 * max(dot(normal, normalize(vec3(0.4, -0.3, 1.0))), 0.0);
  frag = vec4(pc.color.rgb * light, 1.0);
}
