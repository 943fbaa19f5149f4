// The environment: a procedural sky with a sun, and a checkered ground plane
// under the data, so a picture stands on its own. World space.

// An equirectangular image from a file (Renderer::set_environment); g.light.w
// says whether there is one.
layout(set = 0, binding = 14) uniform sampler2D environment_map;

// Two axes perpendicular to up: a (x, or y when x is up) and b = up x a.
void plane_axes(out vec3 a, out vec3 b) {
  a = abs(g.up.x) > 0.5 ? vec3(0, 1, 0) : vec3(1, 0, 0);
  b = cross(g.up.xyz, a);
  a = cross(b, g.up.xyz);
}

// The image's texel for a world direction: u = azimuth around the up axis,
// v = 0 straight up, 1 straight down.
vec3 environment_texel(vec3 dir) {
  vec3 a, b;
  plane_axes(a, b);
  float u = atan(dot(dir, b), dot(dir, a)) * (0.5 / 3.14159265) + 0.5;
  float v = acos(clamp(dot(dir, g.up.xyz), -1.0, 1.0)) * (1.0 / 3.14159265);
  return textureLod(environment_map, vec2(u, v), 0.0).rgb;
}

vec3 sky(vec3 dir) {
  if (g.light.w > 0.5) return environment_texel(dir);
  float h = dot(dir, g.up.xyz);
  vec3 horizon = vec3(0.78, 0.85, 0.92);
  vec3 zenith = vec3(0.22, 0.42, 0.75);
  vec3 below = vec3(0.35, 0.36, 0.38);
  vec3 c = h >= 0.0 ? mix(horizon, zenith, pow(h, 0.6)) : mix(horizon, below, min(-h * 4.0, 1.0));
  float s = max(dot(dir, g.light.xyz), 0.0);
  c += vec3(1.0, 0.9, 0.7) * (pow(s, 900.0) * 6.0 + pow(s, 12.0) * 0.15);
  return c;
}

// Distance along `dir` (normalized) from `origin` to the ground, or -1.
float ground_hit(vec3 origin, vec3 dir) {
  if (g.display.y == 0u) return -1.0;
  float height = dot(origin, g.up.xyz) - g.up.w;
  float rate = dot(dir, g.up.xyz);
  if (height <= 0.0 || rate >= -1e-6) return -1.0;
  return height / -rate;
}

vec3 ground_color(vec3 p, vec3 dir, float dist) {
  // Two axes in the plane, tiles of a power of ten near a tenth of the data.
  vec3 a, b;
  plane_axes(a, b);
  float tile = pow(10.0, floor(log(max(g.scene.w, 1e-6) * 0.25) / log(10.0) + 0.5)) * 0.5;
  vec2 uv = vec2(dot(p, a), dot(p, b)) / tile;
  // Filtered checker: fade to grey where tiles get smaller than a pixel.
  vec2 fw = vec2(dist * g.proj.z * 2.0 * g.viewport.w / tile);
  vec2 s = sign(fract(uv * 0.5) - 0.5);
  float checker = mix(0.5 - 0.5 * s.x * s.y, 0.5, clamp(max(fw.x, fw.y) * 1.5, 0.0, 1.0));
  vec3 base = mix(vec3(0.50, 0.50, 0.52), vec3(0.66, 0.66, 0.68), checker);
  // Soft darkening under the data's footprint, a cheap contact shadow.
  vec3 rel = p - g.scene.xyz;
  rel -= dot(rel, g.up.xyz) * g.up.xyz;
  float shade = 0.85 + 0.15 * smoothstep(0.25, 0.8, length(rel) / max(g.scene.w, 1e-6));
  vec3 c = base * shade * (0.55 + 0.45 * max(dot(g.up.xyz, g.light.xyz), 0.0));
  // Haze towards the horizon.
  float fog = 1.0 - exp(-dist / max(g.scene.w * 8.0, 1e-6));
  return mix(c, sky(dir), fog);
}

vec3 environment(vec3 origin, vec3 dir) {
  float t = ground_hit(origin, dir);
  return t > 0.0 ? ground_color(origin + dir * t, dir, t) : sky(dir);
}
