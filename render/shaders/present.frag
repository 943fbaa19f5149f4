#version 460
// The shaded fluid (the composite's RGBA8 output) into the caller's colour
// image, at the depth the caller's projection gives the fluid's surface, so
// the host's depth test hides it behind the host's own geometry and the
// host can draw on top of it. Pixels without fluid get the background at the
// far plane (where the host has drawn nothing) or are left alone.
#include "common.glsl"
#include "images.glsl"

layout(set = 0, binding = 15, rgba8) uniform readonly image2DArray shaded;
layout(location = 0) out vec4 frag;

// pc.param0, param1: the viewport's origin in the target; param2: bit 0
// background on, bit 1 the target is sRGB (it encodes, so write linear),
// bit 2 the eye (a 2-layer target is presented one layer at a time).
void main() {
  eye = (pc.param2 >> 2) & 1u;
  ivec2 p = ivec2(gl_FragCoord.xy) - ivec2(pc.param0, pc.param1);
  float z = load_depth(g.display.w != 0u ? 1u : 0u, p);
  if (z > 0.0) {
    gl_FragDepth = clamp(g.frustum.z + g.frustum.w / z, 0.0, 1.0);
  } else {
    if ((pc.param2 & 1u) == 0u) discard;
    gl_FragDepth = g.proj.w;
  }
  vec3 c = imageLoad(shaded, ivec3(p, eye)).rgb;
  // An sRGB target encodes what it is given: hand it the value whose exact
  // sRGB encoding is the composite's display value.
  if ((pc.param2 & 2u) != 0u) c = mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
  frag = vec4(c, 1.0);
}
