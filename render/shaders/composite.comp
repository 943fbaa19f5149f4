#version 460
// Normals from the (filtered) depth, then shading: Fresnel reflection of the
// environment, refraction of the background, Beer-Lambert absorption over the
// thickness, specular; or the debug views of vtkOpenGLFluidMapper's display
// modes. Writes the RGBA8 output (sRGB-encoded) and, for tests, eye normals
// and depth.
#include "common.glsl"
#include "images.glsl"
#include "scene.glsl"
#include "colormap.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// The host's scene behind the fluid (RenderTarget::scene_color_image), one
// layer per eye; read only when g.stereo.y says it was given.
layout(set = 0, binding = 16) uniform sampler2DArray scene_color;

uint depth_source() { return g.display.w != 0u ? 1u : 0u; }

vec3 eye_point(ivec2 p, float z) { return eye_ray(vec2(p) + 0.5, g.ray) * z; }

// Of the two one-sided differences, the one with the smaller depth step (or
// the only one with fluid): no smearing across silhouettes.
vec3 one_sided(ivec2 p, ivec2 axis, vec3 centre, float zc) {
  float za = load_depth(depth_source(), p + axis);
  float zb = load_depth(depth_source(), p - axis);
  bool a_ok = za > 0.0, b_ok = zb > 0.0;
  if (a_ok && (!b_ok || abs(za - zc) <= abs(zc - zb))) return eye_point(p + axis, za) - centre;
  if (b_ok) return centre - eye_point(p - axis, zb);
  return vec3(0.0);
}

vec3 surface_normal(ivec2 p, float z, vec3 pe) {
  vec3 dx = one_sided(p, ivec2(1, 0), pe, z);
  vec3 dy = one_sided(p, ivec2(0, 1), pe, z);
  vec3 n = cross(dy, dx);  // image rows go down: this faces the camera
  if (dot(n, n) < 1e-30) return vec3(0.0, 0.0, 1.0);
  n = normalize(n);
  return dot(n, pe) > 0.0 ? -n : n;
}

// The host's scene seen along the bent ray: the point `depth` behind the
// surface point `pe` (eye space), projected back into the image.
vec3 scene_behind(vec3 pe, vec3 bent_world, float depth) {
  vec3 q = pe + mat3(g.view) * bent_world * depth;
  q.z = min(q.z, -1e-6);
  vec2 r = q.xy / -q.z;
  vec2 pixel = vec2((r.x - g.ray.y) / g.ray.x, (r.y - g.ray.w) / g.ray.z) + vec2(pc.param0, pc.param1);
  vec2 uv = clamp(pixel / vec2(textureSize(scene_color, 0).xy), vec2(0.0), vec2(1.0));
  vec3 c = textureLod(scene_color, vec3(uv, float(eye)), 0.0).rgb;
  return g.stereo.z != 0u ? pow(c, vec3(2.2)) : c;
}

// The host's depth of this view (pc.host_depth, passes.cpp's
// shade_with_host_depth): a word per pixel, eyes after each other.
layout(buffer_reference, std430, buffer_reference_align = 4) buffer HostDepth { uint w[]; };
// The host's depth image itself (depth aspect, one layer per eye), when read in place.
layout(set = 0, binding = 17) uniform sampler2DArray host_depth_image;

// The present pass's depth test, done here (pc.param2 bit 1): the fluid
// (eye depth z > 0) is drawn where its depth under the host's projection
// passes the host's (reversed depth: greater or equal), and writes it; a
// pixel without fluid gets the background where the host drew nothing, if
// the background is on (bit 0 clear). Bit 2: the copy is X8_D24, compared
// and stored in its 24 bits as the attachment would.
// Bit 3: the host's depth is read from its image (binding 17) and every
// pixel's depth is written to the copy, which goes back whole.
bool host_depth_test(ivec2 p, float z) {
  HostDepth host_depth = HostDepth(pc.host_depth);
  uint at = (eye * uint(g.viewport.y) + uint(p.y)) * uint(g.viewport.x) + uint(p.x);
  bool d24 = (pc.param2 & 4u) != 0u, in_place = (pc.param2 & 8u) != 0u;
  uint bits;
  float host;
  if (in_place) {
    host = texelFetch(host_depth_image, ivec3(p + ivec2(pc.param0, pc.param1), eye), 0).r;
    bits = d24 ? uint(host * 16777215.0 + 0.5) : floatBitsToUint(host);
    host_depth.w[at] = bits;
  } else {
    bits = host_depth.w[at];
    host = d24 ? float(bits & 0xffffffu) * (1.0 / 16777215.0) : uintBitsToFloat(bits);
  }
  bool reversed = g.proj.w < 0.5;  // the far plane at depth 0
  if (z <= 0.0) return (pc.param2 & 1u) == 0u && (reversed ? host <= g.proj.w : host >= g.proj.w);
  float d = clamp(g.frustum.z + g.frustum.w / z, 0.0, 1.0);
  uint d_bits = d24 ? uint(d * 16777215.0 + 0.5) : floatBitsToUint(d);
  if (d24) d = float(d_bits) * (1.0 / 16777215.0);
  if (reversed ? d < host : d > host) return false;
  host_depth.w[at] = d24 ? (bits & 0xff000000u) | d_bits : d_bits;
  return true;
}

vec3 to_srgb(vec3 c) {
  c = max(c, 0.0);
  c = c / (1.0 + 0.12 * c);  // gentle shoulder for the sun glint
  return pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2));
}

void main() {
  eye = gl_GlobalInvocationID.z;
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, ivec2(g.viewport.xy)))) return;
  vec3 de = eye_ray(vec2(p) + 0.5, g.ray);
  vec3 dir = normalize(mat3(g.inv_view) * de);
  vec3 origin = g.eye.xyz;  // the eye's world position
  uint mode = g.display.x;

  float z = load_depth(depth_source(), p);
  float dist = z * length(de);
  float tg = ground_hit(origin, dir);
  bool fluid = z > 0.0 && (tg < 0.0 || dist < tg);
  vec3 color;
  vec3 n = vec3(0.0);
  if (!fluid) {
    color = mode >= 2u && mode <= 7u ? vec3(0.0) : environment(origin, dir);
  } else {
    vec3 pe = de * z;
    n = surface_normal(p, z, pe);
    vec2 uv = (vec2(p) + 0.5) * g.viewport.zw;
    vec2 th = g.filter_modes.w != 0u ? texture(thick_a_tex, vec3(uv, eye)).xy : texture(thick_raw_tex, vec3(uv, eye)).xy;
    float thickness = th.x;
    float attr = th.x > 0.0 ? th.y / th.x : 0.0;
    vec3 nw = normalize(mat3(g.inv_view) * n);
    vec3 pw = origin + dir * dist;
    vec3 l = normalize(g.light.xyz);
    float ior = g.shade.x;
    float f0 = (ior - 1.0) / (ior + 1.0);
    f0 *= f0;
    float cos_v = clamp(dot(nw, -dir), 0.0, 1.0);
    float fresnel = f0 + (1.0 - f0) * pow(1.0 - cos_v, 5.0);
    vec3 refl_dir = reflect(dir, nw);
    vec3 reflection = environment(pw + nw * g.radius.x * 0.01, refl_dir);
    float spec = pow(max(dot(nw, normalize(l - dir)), 0.0), 300.0) * 3.0 + pow(max(dot(nw, normalize(l - dir)), 0.0), 40.0) * 0.15;
    bool scalar = g.color.z != 0.0;
    vec3 tint = scalar ? colormap(attr, uint(g.color.w)) : vec3(1.0);

    if (mode == 2u || mode == 3u) {
      color = n * 0.5 + 0.5;
    } else if (mode == 4u || mode == 5u) {
      float centre = length(g.scene.xyz - origin);
      float v = clamp((z - (centre - 0.5 * g.scene.w)) / max(g.scene.w, 1e-6), 0.0, 1.0);
      color = vec3(1.0 - v);
    } else if (mode == 6u || mode == 7u) {
      color = vec3(1.0 - exp(-thickness / max(8.0 * g.radius.x, 1e-9)));
    } else if (mode == 8u) {
      vec3 refr = refract(dir, nw, 1.0 / ior);
      if (dot(refr, refr) < 1e-6) refr = refl_dir;
      vec3 bent = normalize(dir + (refr - dir) * g.shade.y);
      vec3 background = g.stereo.y != 0u ? scene_behind(pe, bent, max(thickness, g.radius.x)) : environment(pw, bent);
      vec3 absorb = (scalar ? (1.0 - tint) + 0.05 : g.attenuation.rgb) * g.shade.w;
      vec3 transmit = exp(-absorb * thickness);
      // A little in-scattering so deep liquid is not black.
      vec3 scatter = (1.0 - transmit) * (scalar ? tint : vec3(0.05, 0.22, 0.3)) * 0.25 * sky(g.up.xyz);
      color = (1.0 - fresnel) * (background * transmit + scatter) + (fresnel + g.shade.z) * reflection +
              spec * vec3(1.0, 0.95, 0.85);
    } else {
      vec3 base = scalar ? tint : g.opaque_color.rgb;
      vec3 diffuse = base * (0.3 + 0.7 * max(dot(nw, l), 0.0));
      color = mix(diffuse, reflection, clamp(fresnel + g.shade.z, 0.0, 1.0)) + spec * vec3(1.0, 0.95, 0.85);
    }
  }
  bool raw_view = mode >= 2u && mode <= 7u;
  // pc.param0, param1: the view's origin in the output; param2 bit 0: leave
  // pixels without fluid alone (the caller's image, background off); bit 1:
  // the host's depth decides (host_depth_test).
  bool store = (pc.param2 & 2u) != 0u ? host_depth_test(p, z) : fluid || (pc.param2 & 1u) == 0u;
  if (store) imageStore(out_color, ivec3(p + ivec2(pc.param0, pc.param1), eye), vec4(raw_view ? clamp(color, 0.0, 1.0) : to_srgb(color), 1.0));
  if (g.display.z != 0u) imageStore(out_aux, ivec3(p, eye), vec4(n, fluid ? z : 0.0));
}
