#version 460
// Compute splatting's integer targets to the float buffers the filters and
// shading read: pc.param0 = 0 depth (full resolution), 1 thickness. Each
// integer texel is reset as it is read, ready for the next frame's splats:
// cheaper than a separate clear.
#include "common.glsl"
#include "images.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

void main() {
  eye = gl_GlobalInvocationID.z;
  ivec3 p = ivec3(gl_GlobalInvocationID);
  if (pc.param0 == 0u) {
    if (any(greaterThanEqual(p.xy, imageSize(depth_raw).xy))) return;
    uint bits = imageLoad(depth_u, p).x;
    imageStore(depth_raw, p, vec4(bits == 0xffffffffu ? 0.0 : uintBitsToFloat(bits)));
    imageStore(depth_u, p, uvec4(0xffffffffu));
  } else {
    if (any(greaterThanEqual(p.xy, imageSize(thick_raw).xy))) return;
    vec2 t = vec2(imageLoad(thick_u, p).x, imageLoad(thick_attr_u, p).x) * g.splat.y;
    imageStore(thick_raw, p, vec4(t, 0.0, 0.0));
    imageStore(thick_u, p, uvec4(0u));
    imageStore(thick_attr_u, p, uvec4(0u));
  }
}
