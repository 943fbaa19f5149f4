#version 460
// Anisotropic particles (Yu & Turk 2013), after band_scatter, in three steps
// (pc.step) over the particles within one voxel side of each (its voxel's
// list and the 26 around it), weighted 1 - (r / side)^3 by their distance:
// 0. its centre's shift: Yu & Turk's smoothing of the centres,
//    c = x + lambda (weighted mean of the neighbours - x), which takes the
//    jitter out of a resting surface and pulls it in by a fraction of h;
//    drawn with lambda = kSmoothing;
// 1. its shape, from the weighted covariance of the neighbours' centres
//    smoothed with lambda = kShapeSmoothing (Yu & Turk's 0.9), about its
//    own: the smoothing takes the jitter out of the orientations too,
//    while the drawn centres move less, so that thin sheets keep their
//    thickness (measured in docs/render.md, "Flat water"):
//    A = R S^2 R^T (R: the ellipsoid's axes, S: its
//    radii in units of the particle's radius), so that the ellipsoid of a
//    particle of radius r at c is (x - c)^T A^-1 (x - c) <= r^2;
// 2. its drawn centre, anew: along the ellipsoid's shortest axis n, the
//    weighted mean height of the neighbours in its own layer (those whose
//    offset along n is under kLayer side; the particle included), so the
//    top layer of a resting surface draws at its layer's mean height and
//    the two layers of a thin sheet stay apart; across n, step 0's shift.
//    Step 0's whole-neighbourhood mean left each top particle half its own
//    jitter in height (measured in docs/render.md, "Flat water").
// Per particle 5 words (common.glsl's load_item reads them): A as 6 halves
// in 3 words (xx xy, xz yy, yz zz), then the shift as 3 halves in units of
// h = side / 2 (x y, z 0). The radii keep the sphere's volume (their
// product is 1), the largest is at most kMaxRatio times the smallest (so at
// most kMaxRatio^(2/3) = common.glsl's kLongestAxis), and a particle with
// fewer than kMinNeighbours near it stays a sphere (A = I, no shift).
// Entries marked in pc.marks (blobs) are neither shaped nor neighbours.
// The sums over the neighbours are kept in 64-bit fixed point: the order
// of a voxel's list follows the scatter's atomics, and float sums in that
// order made two draws of one frame differ in the last bits.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "band.glsl"

const uint kMinNeighbours = 6u;
const float kMaxRatio = 4.0;
const float kSmoothing = 0.5;       // lambda of the drawn centres (common.glsl's largest_shift)
const float kShapeSmoothing = 0.9;  // lambda of the centres the shapes are taken from
// Step 2's layer: neighbours whose offset along n is under kLayer.x sides
// count fully, fading out by kLayer.y (0.4 and 0.7 particle spacings where
// the side is 2 spacings: a lattice's next layer is 1 spacing away).
const vec2 kLayer = vec2(0.15, 0.3);

// Fixed point: 2^24 units per voxel side (offsets) or side^2 (their
// products); a neighbour's terms are at most 9 side^2, so 6e10 of them fit.
const float kFixed = 16777216.0;
int64_t to_fixed(float v) { return int64_t(round(v * kFixed)); }
i64vec3 to_fixed(vec3 v) { return i64vec3(round(v * kFixed)); }
vec3 from_fixed(i64vec3 v) { return vec3(v) / kFixed; }

struct Moments {
  int64_t w0;   // sum of weights
  i64vec3 w1;   // weighted sum of offsets from the particle, in sides
  i64vec3 w2d;  // weighted sum of their outer products: the diagonal (xx, yy, zz)
  i64vec3 w2o;  // and the rest (xy, xz, yz)
  uint near;    // particles within reach, the particle itself included
};

bool marked(uint i) {
  return pc.marks != uvec2(0u) && ((Uints(pc.marks).v[i >> 5] >> (i & 31u)) & 1u) != 0u;
}

// Step 0's shift of particle j (world), as step 1 reads it back.
vec3 shift_of(uint j) {
  Uints shapes = Uints(pc.shapes);
  vec2 xy = unpackHalf2x16(shapes.v[5u * j + 3u]);
  return vec3(xy, unpackHalf2x16(shapes.v[5u * j + 4u]).x) * (0.5 * pc.side);
}

// The neighbours in slot s of the particle at p: weighted by their distance
// from p; their offsets taken from `centre` (step 0: p; step 1: its
// centre smoothed for shapes, to theirs).
void gather_slot(uint s, vec3 p, vec3 centre, inout Moments m) {
  if (s == kEmpty) return;
  uint end = START(s);
  for (uint k = end - COUNT(s); k < end; ++k) {
    uint j = LIST(k);
    if (marked(j)) continue;
    vec3 x = particle(j);
    float q = length(x - p) / pc.side;
    if (q >= 1.0) continue;
    float w = 1.0 - q * q * q;
    vec3 d = ((pc.step == 0u ? x : x + (kShapeSmoothing / kSmoothing) * shift_of(j)) - centre) / pc.side;
    m.w0 += to_fixed(w);
    m.w1 += to_fixed(w * d);
    m.w2d += to_fixed(w * d * d);
    m.w2o += to_fixed(w * d.xxy * d.yzz);
    m.near += 1u;
  }
}

// Step 2: the neighbours in slot s of the particle at p, in its layer
// across n: their weights (x) and weighted heights along n in sides (y).
void gather_layer(uint s, vec3 p, vec3 n, inout i64vec2 layer) {
  if (s == kEmpty) return;
  uint end = START(s);
  for (uint k = end - COUNT(s); k < end; ++k) {
    uint j = LIST(k);
    if (marked(j)) continue;
    vec3 d = particle(j) - p;
    float q = length(d) / pc.side;
    if (q >= 1.0) continue;
    float height = dot(d, n) / pc.side;
    float w = (1.0 - q * q * q) * (1.0 - smoothstep(kLayer.x, kLayer.y, abs(height)));
    layer += i64vec2(to_fixed(w), to_fixed(w * height));
  }
}

// Eigenvalues and eigenvectors (columns) of symmetric `a`: cyclic Jacobi
// rotations, each zeroing one off-diagonal pair.
void eigen(mat3 a, out vec3 values, out mat3 vectors) {
  mat3 v = mat3(1.0);
  for (int sweep = 0; sweep < 6; ++sweep) {
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        float apq = a[q][p];
        if (abs(apq) <= 1e-12 * (abs(a[p][p]) + abs(a[q][q]))) continue;
        float theta = (a[q][q] - a[p][p]) / (2.0 * apq);
        float t = (theta >= 0.0 ? 1.0 : -1.0) / (abs(theta) + sqrt(theta * theta + 1.0));
        float c = inversesqrt(t * t + 1.0);
        float s = t * c;
        mat3 j = mat3(1.0);
        j[p][p] = c;
        j[q][q] = c;
        j[q][p] = s;   // row p, column q
        j[p][q] = -s;  // row q, column p
        a = transpose(j) * a * j;
        v = v * j;
      }
    }
  }
  values = vec3(a[0][0], a[1][1], a[2][2]);
  vectors = v;
}

mat3 load_shape(uint i) {
  Uints shapes = Uints(pc.shapes);
  vec2 a = unpackHalf2x16(shapes.v[5u * i]);
  vec2 b = unpackHalf2x16(shapes.v[5u * i + 1u]);
  vec2 c = unpackHalf2x16(shapes.v[5u * i + 2u]);
  return mat3(a.x, a.y, b.x, a.y, b.y, c.x, b.x, c.x, c.y);
}

void store_shape(uint i, mat3 a) {
  Uints shapes = Uints(pc.shapes);
  shapes.v[5u * i] = packHalf2x16(vec2(a[0][0], a[1][0]));
  shapes.v[5u * i + 1u] = packHalf2x16(vec2(a[2][0], a[1][1]));
  shapes.v[5u * i + 2u] = packHalf2x16(vec2(a[2][1], a[2][2]));
}

void store_shift(uint i, vec3 shift) {
  Uints shapes = Uints(pc.shapes);
  vec3 in_h = shift * (2.0 / pc.side);
  shapes.v[5u * i + 3u] = packHalf2x16(in_h.xy);
  shapes.v[5u * i + 4u] = packHalf2x16(vec2(in_h.z, 0.0));
}

// Volume-keeping radii proportional to the covariance's eigenvalues (Yu &
// Turk's choice), clamped to kMaxRatio: the shape matrix.
mat3 shape_of(mat3 covariance) {
  vec3 values;
  mat3 vectors;
  eigen(covariance, values, vectors);
  float largest = max(values.x, max(values.y, values.z));
  if (!(largest > 0.0)) return mat3(1.0);
  vec3 clamped = max(values, vec3(largest / kMaxRatio));
  vec3 radii = clamped / pow(clamped.x * clamped.y * clamped.z, 1.0 / 3.0);
  return vectors * mat3(radii.x * radii.x, 0.0, 0.0, 0.0, radii.y * radii.y, 0.0, 0.0, 0.0, radii.z * radii.z) *
         transpose(vectors);
}

void main() {
  Params g = Params(pc.params);
  if (g.fits == 0u || pc.shapes == uvec2(0u)) return;
  // Particles in the order of the voxels' lists: neighbouring invocations
  // read the same 27 voxels' particles, which stay in cache. In particle
  // order a file's LOD tiers scatter a warp over whole cells, and this pass
  // took 35.7 ms for 10M on the H100, against 19.6 in list order.
  for (uint k = first_item() + gl_LocalInvocationIndex; k < pc.n; k += round_stride()) {
    uint i = LIST(k);
    if (marked(i)) {
      if (pc.step == 0u) store_shift(i, vec3(0.0));
      if (pc.step == 1u) store_shape(i, mat3(1.0));
      continue;
    }
    vec3 p = particle(i);
    uint s = SLOT(i);
    uvec3 c = cell_of_key(key_of_slot(s, g), g);
    if (pc.step == 2u) {
      mat3 a = load_shape(i);
      if (a == mat3(1.0)) continue;  // a sphere: no layer to keep to
      vec3 values;
      mat3 vectors;
      eigen(a, values, vectors);
      vec3 n = values.x <= min(values.y, values.z) ? vectors[0] : values.y <= values.z ? vectors[1] : vectors[2];
      i64vec2 layer = i64vec2(0);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            ivec3 d = ivec3(dx, dy, dz);
            gather_layer(d == ivec3(0) ? s : neighbour_slot(c, d, g), p, n, layer);
          }
      vec3 across = shift_of(i);
      across -= dot(across, n) * n;
      vec3 shift = across + (float(layer.y) / float(layer.x) * pc.side) * n;
      // At most common.glsl's largest_shift, h, which the cull allows for.
      float most = 0.5 * pc.side;
      store_shift(i, length(shift) > most ? shift * (most / length(shift)) : shift);
      continue;
    }
    vec3 centre = pc.step == 0u ? p : p + (kShapeSmoothing / kSmoothing) * shift_of(i);
    Moments m = Moments(0l, i64vec3(0), i64vec3(0), i64vec3(0), 0u);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          ivec3 d = ivec3(dx, dy, dz);
          gather_slot(d == ivec3(0) ? s : neighbour_slot(c, d, g), p, centre, m);
        }
    bool shaped = m.near - 1u >= kMinNeighbours;
    float w0 = float(m.w0) / kFixed;
    vec3 mean = from_fixed(m.w1) / w0;
    if (pc.step == 0u) {
      store_shift(i, shaped ? kSmoothing * pc.side * mean : vec3(0.0));
    } else {
      vec3 diagonal = from_fixed(m.w2d) / w0, rest = from_fixed(m.w2o) / w0;
      mat3 second = mat3(diagonal.x, rest.x, rest.y, rest.x, diagonal.y, rest.z, rest.y, rest.z, diagonal.z);
      store_shape(i, shaped ? shape_of(second - outerProduct(mean, mean)) : mat3(1.0));
    }
  }
}
