// Colormaps for colouring by attribute, t in [0, 1]. Polynomial fits.
vec3 viridis(float t) {
  const vec3 c0 = vec3(0.2777, 0.0054, 0.3341), c1 = vec3(0.1051, 1.4046, 1.3846);
  const vec3 c2 = vec3(-0.3309, 0.2148, 0.0951), c3 = vec3(-4.6342, -5.7991, -19.3324);
  const vec3 c4 = vec3(6.2283, 14.1799, 56.6906), c5 = vec3(4.7764, -13.7451, -65.3530);
  const vec3 c6 = vec3(-5.4355, 4.6459, 26.3124);
  return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
}
vec3 turbo(float t) {
  const vec3 c0 = vec3(0.1140, 0.0628, 0.2248), c1 = vec3(6.7164, 3.1822, 7.5715);
  const vec3 c2 = vec3(-66.0940, -4.9279, -10.0943), c3 = vec3(228.7660, 25.0499, -91.5411);
  const vec3 c4 = vec3(-334.8351, -69.3175, 288.5858), c5 = vec3(218.7637, 67.5215, -305.2045);
  const vec3 c6 = vec3(-52.8890, -21.5453, 110.5174);
  return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
}
vec3 coolwarm(float t) {
  vec3 cool = vec3(0.230, 0.299, 0.754), mid = vec3(0.865, 0.865, 0.865), warm = vec3(0.706, 0.016, 0.150);
  return t < 0.5 ? mix(cool, mid, t * 2.0) : mix(mid, warm, t * 2.0 - 1.0);
}
vec3 blues(float t) { return mix(vec3(0.87, 0.92, 0.97), vec3(0.03, 0.19, 0.42), t); }

vec3 colormap(float t, uint which) {
  t = clamp(t, 0.0, 1.0);
  vec3 c = which == 0u ? viridis(t) : which == 1u ? coolwarm(t) : which == 2u ? turbo(t) : blues(t);
  return clamp(c, 0.0, 1.0);
}
