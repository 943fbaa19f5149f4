// Shared by every sluice shader: the per-frame uniforms of each eye (mirrored
// by struct Globals in src/gpu_types.h; keep the two in step), the buffer layouts
// reached through buffer device addresses, and the push constants.
#include "frame_layout.glsl"

struct Globals {
  mat4 view;            // world -> eye
  mat4 inv_view;        // eye -> world
  vec4 planes[5];       // world frustum planes (left, right, bottom, top, near): inside when dot(n, x) + w >= 0
  vec4 eye;             // world eye position; w: near plane distance
  vec4 viewport;        // output width, height, 1/width, 1/height
  vec4 thick_viewport;  // the thickness buffer's width, height, 1/width, 1/height
  vec4 proj;            // P00 (x scale), y scale (-P11: image rows go down), 1 / y scale (tan of half the vertical fov), far-plane depth of the target
  vec4 radius;          // sphere radius, largest point size (px), largest splat (px), near-cull distance
  vec4 lod;             // level, threshold -ln(level), 1 / reference distance, largest splat scale
  uvec4 modes;          // lod mode, lod random, position coding, has colour attribute
  vec4 color;           // colour range min, 1 / (max - min), scalar visibility, colormap
  vec4 filter_params;   // sigma (world), largest kernel radius (px), delta (world), mu (world)
  uvec4 filter_modes;   // method, iterations, thickness radius (px), thickness iterations
  vec4 shade;           // refractive index, refraction scale, additional reflection, attenuation scale
  vec4 attenuation;     // rgb absorption colour
  vec4 opaque_color;    // rgb
  uvec4 display;        // display mode, ground on, write aux, depth filtered
  vec4 up;              // world up axis; w: ground height along it
  vec4 light;           // world direction towards the sun
  vec4 scene;           // scene centre xyz; w: scene extent (diagonal)
  vec4 splat;           // thickness fixed-point scale (units per world unit), its inverse, largest small-splat area (px)
  vec4 frustum;         // ndc offset x, y of an asymmetric frustum; target depth = z + w / distance
  vec4 ray;             // pixel centre -> eye ray (z = -1): x = px * ray.x + ray.y, y = py * ray.z + ray.w
  vec4 thick_ray;       // the same for the thickness buffer's pixels
  uvec4 stereo;         // x: eyes drawn in one pass (1, or 2 with multiview targets); y: the host's scene colour given; z: it holds display values
};
// One Globals per eye (the second is unused in mono).
layout(set = 0, binding = 0, std140) uniform Views { Globals views[2]; };
// The eye (target layer) this invocation works for, set first in main():
// compute passes take it from the dispatch's z, raster passes from
// gl_ViewIndex. 0 in mono.
uint eye = 0u;
#define g views[eye]

layout(buffer_reference, std430, buffer_reference_align = 8) buffer Blocks { uvec2 b[]; };
// The draw list: one uvec2 per kept particle, x = its 256-particle block
// in Blocks, y = index in the block (8 bits) | splat growth (12-bit unorm
// over 1..largest scale) << 8 | colour attribute (12-bit unorm) << 20.
// 8 bytes: the cull writes half of what world positions would take.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer Draws { uvec2 d[]; };

// Counters and indirect arguments, reset before every cull.
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Args {
  uint vertex_count;    // VkDrawIndirectCommand
  uint instance_count;
  uint first_vertex;
  uint first_instance;
  uint groups_x;        // VkDispatchIndirectCommand for the particle pass
  uint groups_y;
  uint groups_z;
  uint block_count;     // visible 256-particle blocks
  uint visible_chunks;
  uint splat_x;         // VkDispatchIndirectCommand for the small-splat pass
  uint splat_y;
  uint splat_z;
  uint big_count;       // splats too large for one thread
  uint big_x;           // VkDispatchIndirectCommand for the large-splat pass
  uint big_y;
  uint big_z;
};
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Items { uint i[]; };
// [0]: 1 when valid; then one bit per particle of the frame, 1: surface.
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Surface { uint w[]; };

layout(push_constant) uniform Push {
  uvec2 particles;
  uvec2 chunks;
  uvec2 attributes;
  uvec2 blocks;
  uvec2 draws;
  uvec2 args;
  uvec2 big;    // Items: draw-list indices of the large splats
  uvec2 surface;  // Surface of a frame classified on the GPU (src/frame_band.h), or 0
  uvec2 shapes;   // Shapes: anisotropic particles' shape matrices (src/frame_band.h), or 0: spheres
  uint chunk_count;
  uint param0;  // per pass: filter direction, thickness pass flag, ...
  uint param1;
  uint param2;
  uvec2 host_depth;  // HostDepth: the host's depth of this view, copied out for the shading pass to test and write, or 0
} pc;

// [0]: 1 once written; [1]: h (float, world), then per particle of the
// frame 5 words (band_ellipsoids.comp writes them): its ellipsoid's shape
// matrix A as 6 halves (xx xy, xz yy, yz zz), its centre's shift in units
// of h as 3 halves (x y, z 0).
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Shapes { uint w[]; };

// Whether this pipeline draws anisotropic particles (specialization
// constant 0, shaders.h's compute_pipeline): false leaves their code out, so
// the spheres' splatting keeps its speed.
layout(constant_id = 0) const bool kEllipsoids = false;

const uint kBlock = 256;  // particles per cull workgroup
// The longest an ellipsoid's axis gets, in particle radii: its radii are at
// most 4 times apart and their product is 1 (band_ellipsoids.comp), 4^(2/3).
const float kLongestAxis = 2.5198421;

// World position and stable LOD value of particle `index` of chunk `c`.
void decode_particle(Chunk c, uint index, out vec3 pos, out uint lod_value) {
  decode_position(pc.particles, g.modes.z != 0u, c, index, pos, lod_value);
}

struct DrawItem {
  vec3 pos;      // world
  float radius;  // world, grown in density-preserving LOD; blobs: how far their splat reaches
  float attr;    // colour attribute, 0..1
  float count;   // blobs: particles the blob stands for; 0: a particle
  float sigma;   // blobs: the splat's standard deviation (world)
  bool ellipsoid;  // anisotropic: the particle is the ellipsoid (x - pos)^T shape^-1 (x - pos) <= radius^2
  mat3 shape;      // world; identity unless `ellipsoid`
};

// Particle `index`'s ellipsoid: its shape matrix; its centre's shift (world).
mat3 load_shape(uint index, out vec3 shift) {
  Shapes s = Shapes(pc.shapes);
  uint at = 2u + 5u * index;
  vec2 a = unpackHalf2x16(s.w[at]);
  vec2 b = unpackHalf2x16(s.w[at + 1u]);
  vec2 c = unpackHalf2x16(s.w[at + 2u]);
  shift = vec3(unpackHalf2x16(s.w[at + 3u]), unpackHalf2x16(s.w[at + 4u]).x) * uintBitsToFloat(s.w[1]);
  return mat3(a.x, a.y, b.x, a.y, b.y, c.x, b.x, c.x, c.y);
}

// How far an ellipsoid's centre may move from its particle: kSmoothing
// (0.5) times the reach of its neighbours, 2h (band_ellipsoids.comp).
float largest_shift() {
  if (pc.shapes == uvec2(0u) || Shapes(pc.shapes).w[0] == 0u) return 0.0;
  return uintBitsToFloat(Shapes(pc.shapes).w[1]);
}

// A blob's splat (section 4 of papers/001, eq. 4.2, normalized): a Gaussian
// across the view whose integral is `count` particle volumes, so the blobs
// add the thickness their particles would have added. Its spread is that of
// the particles' chords: uniform centres over the voxel (d^2/12 per axis)
// blurred by one sphere's chord profile (r^2/5), widened to the voxel's
// half-side so neighbouring blobs sum to an even thickness.
float blob_sigma(float voxel, float r) {
  return sqrt(max(voxel * voxel / 12.0 + r * r / 5.0, 0.25 * voxel * voxel));
}
// Splats end at this many sigma: the disc holds 1 - exp(-2.5^2 / 2) = 95.6%
// of the Gaussian, and blob_thickness() scales the rest back in, so a blob
// adds its whole volume. At 3 sigma (98.9%, not scaled) the blobs' splats
// cost 1.44x the pixels: the narrow band's 100M-particle frame in both eyes
// of 2064x2208 took 9.85 ms on the H100 (docs/measurements.md).
const float kBlobReach = 2.5;
const float kBlobDisc = 0.95606;  // 1 - exp(-kBlobReach^2 / 2)

// Thickness (world) a blob adds along a ray passing `d2` (squared, world)
// from its centroid, within kBlobReach sigma.
float blob_thickness(float count, float sigma, float d2) {
  float volume = count * (4.0 / 3.0) * 3.14159265 * g.radius.x * g.radius.x * g.radius.x;
  return volume / (6.28318531 * sigma * sigma * kBlobDisc) * exp(-0.5 * d2 / (sigma * sigma));
}

DrawItem load_item(uint item) {
  uvec2 d = Draws(pc.draws).d[item];
  uvec2 block = Blocks(pc.blocks).b[d.x];
  Chunk c = Chunks(pc.chunks).c[block.x];
  DrawItem it;
  uint lod_value;
  uint index = c.first + (block.y & 0x7fffffffu) + (d.y & 0xffu);
  decode_particle(c, index, it.pos, lod_value);
  float growth = float((d.y >> 8) & 0xfffu) * (1.0 / 4095.0);
  it.radius = g.radius.x * (1.0 + growth * (g.lod.w - 1.0));
  it.attr = float(d.y >> 20) * (1.0 / 4095.0);
  it.count = 0.0;
  it.sigma = 0.0;
  it.ellipsoid = kEllipsoids && c.kind == 0u && pc.shapes != uvec2(0u) && Shapes(pc.shapes).w[0] != 0u;
  it.shape = mat3(1.0);
  if (it.ellipsoid) {
    vec3 shift;
    it.shape = load_shape(index, shift);
    it.pos += shift;
  }
  if (c.kind == 1u) {
    float grow = 1.0 + growth * (g.lod.w - 1.0);  // density-preserving LOD: it stands for grow^3 times as many
    it.count = float(lod_value) * grow * grow * grow;
    it.sigma = blob_sigma(c.voxel, g.radius.x);
    it.radius = kBlobReach * it.sigma;
  }
  return it;
}

// Extent of tan(angle) covered by a circle of radius r at (u, d) (d > 0 in
// front of the eye): tan(phi -/+ alpha), from the two tangent lines.
vec2 tangent_range(float u, float d, float r) {
  float t = sqrt(max(u * u + d * d - r * r, 0.0));
  float lo_den = d * t + u * r;
  float hi_den = d * t - u * r;
  float lo = lo_den > 0.0 ? (u * t - r * d) / lo_den : -1e6;
  float hi = hi_den > 0.0 ? (u * t + r * d) / hi_den : 1e6;
  return vec2(lo, hi);
}

// The exact screen-space bounding box (pixels of a viewport `vp`) of the
// perspective projection of a sphere at eye-space c with radius r.
void sphere_bounds(vec3 c, float r, vec4 vp, out vec2 lo, out vec2 hi) {
  float d = -c.z;
  vec2 tx = tangent_range(c.x, d, r) * g.proj.x + g.frustum.x;    // ndc x range
  vec2 ty = tangent_range(c.y, d, r) * -g.proj.y + g.frustum.y;   // ndc y (flipped: image rows go down)
  lo = (vec2(tx.x, min(ty.x, ty.y)) * 0.5 + 0.5) * vp.xy;
  hi = (vec2(tx.y, max(ty.x, ty.y)) * 0.5 + 0.5) * vp.xy;
}

// An ellipsoid in eye space: its quadric matrix Q = radius^2 V shape V^T
// (V: the view's rotation), so that it is (x - c)^T Q^-1 (x - c) <= 1.
mat3 eye_quadric(DrawItem it) {
  mat3 v = mat3(g.view);
  return it.radius * it.radius * (v * it.shape * transpose(v));
}

// tan(angle) range along one image axis a (x or y) covered by an ellipsoid
// at eye-space c with quadric Q: the planes x_a + u z = 0 through the eye
// that touch it, (c_a + u c_z)^2 = Q_aa + 2 u Q_az + u^2 Q_zz.
vec2 quadric_range(float ca, float cz, float qaa, float qaz, float qzz) {
  float a = cz * cz - qzz;
  if (a <= 0.0) return vec2(-1e6, 1e6);  // it reaches the eye's plane
  float b = ca * cz - qaz;
  float root = sqrt(max(b * b - a * (ca * ca - qaa), 0.0));
  return vec2((-b - root) / a, (-b + root) / a);
}

// The exact screen-space bounding box (pixels of a viewport `vp`) of the
// perspective projection of an ellipsoid at eye-space c with quadric q.
void ellipsoid_bounds(vec3 c, mat3 q, vec4 vp, out vec2 lo, out vec2 hi) {
  vec2 tx = quadric_range(c.x, c.z, q[0][0], q[2][0], q[2][2]) * g.proj.x + g.frustum.x;
  vec2 ty = quadric_range(c.y, c.z, q[1][1], q[2][1], q[2][2]) * -g.proj.y + g.frustum.y;
  lo = (vec2(tx.x, min(ty.x, ty.y)) * 0.5 + 0.5) * vp.xy;
  hi = (vec2(tx.y, max(ty.x, ty.y)) * 0.5 + 0.5) * vp.xy;
}

// A ray from the eye along unit n against the ellipsoid at eye-space c with
// inverse quadric b = Q^-1: false on a miss; else the distance along n to
// the near hit and the chord through it. Solved from the ray's closest
// approach to the centre, so small, far ellipsoids stay exact in float.
bool ray_ellipsoid(vec3 c, mat3 b, vec3 n, out float near, out float chord) {
  float tc = dot(n, c);
  vec3 p = c - tc * n;  // the centre, seen from the closest approach
  vec3 bn = b * n;
  float qa = dot(n, bn), qb = dot(p, bn), qc = dot(p, b * p) - 1.0;
  float disc = qb * qb - qa * qc;
  near = 0.0;
  chord = 0.0;
  if (disc < 0.0) return false;
  float root = sqrt(disc);
  near = tc + (qb - root) / qa;
  chord = 2.0 * root / qa;
  return true;
}

// Eye-space ray direction through a pixel (not normalized; z = -1), with the
// coefficients of the image it belongs to (g.ray or g.thick_ray): two FMAs.
vec3 eye_ray(vec2 pixel, vec4 k) {
  return vec3(pixel.x * k.x + k.y, pixel.y * k.z + k.w, -1.0);
}
