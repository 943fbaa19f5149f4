// Shared by the narrow-band classifier's passes (band_*.comp; host side in
// src/band_classifier.cpp): the voxel hash table, the grid and the buffers,
// reached through buffer device addresses in the push constants.
//
// The grid is io::classify_narrow_band's, computed with the same float
// operations (`precise`: no fused multiply-add), so that every particle
// lands in the same voxel as on the CPU. Voxels are keyed by their linear
// cell (x * dims.y + y) * dims.z + z; cells 0 and dims - 1 of each axis are
// the outside and are never occupied.
//
// Where the grid has no more cells than the table has slots (a fluid body,
// not spray flung far away), the table is dense: a voxel's slot is its cell
// and a slot is occupied when its count is not zero, so neighbours are
// found by address and lie next to each other in memory. Otherwise slots
// hold keys, placed by hashing with linear probing.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(local_size_x = 256) in;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Floats { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Uints { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4s { vec4 v[]; };

// Written by band_bounds and band_grid, counters by the other passes;
// mirrored by BandParams in src/band_classifier.cpp.
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Params {
  uint lo[3];          // the box, as order-preserving uint (ordered())
  uint fits;           // band_grid: 1 when the grid's cells fit 32 bits
  uint hi[3];
  uint voxels;         // occupied voxels
  float origin[3];     // a quarter voxel below the box
  uint cursor;         // particles given a place in the voxel lists so far
  float last_cell[3];  // the highest cell index a particle may get, per axis
  uint blobs;          // blobs written
  uint dims[3];        // cells per axis, the outside layer included
  uint l1;             // L1 voxels
  uint counts[4];      // particles per layer (io::BandLayer)
  uint l2;             // selected L2 voxels
  uint dense;          // band_grid: 1 when slot = cell (cells <= capacity)
  uint cells;          // band_grid: dims.x * dims.y * dims.z, when it fits 32 bits
  uint pad;
};

layout(push_constant) uniform Push {
  uvec2 xyz;        // Floats: x, y, z per particle
  uvec2 attr;       // Floats[n]: an attribute per particle whose mean each blob takes; 0: none
  uvec2 params;     // Params
  uvec2 table;      // Uints[5 capacity], per slot: KEY COUNT START L1MARK L2MARK (below)
  uvec2 particles;  // Uints[5 n], per particle: SLOT LIST VOXEL LAYER BLOB_OF (below)
  uvec2 blobs;      // Vec4s[n]: centroid, count (as uint bits) (with_blobs)
  uvec2 blob_attr;  // Floats[n]: each blob's mean of attr (with_blobs and attr)
  uint n;           // particles (at most 2^28: 5 capacity indices fit 32 bits)
  uint mask;        // capacity - 1 (capacity: a power of two >= 2n)
  float inverse;    // 1 / voxel side
  float side;       // voxel side
  uint n1;          // floor((d / h)^3): L1 voxels with at most this many particles select L2
  float reach2;     // (min(2h, d))^2: a particle with nobody nearer is isolated
  uint with_blobs;
  uint step;        // band_ellipsoids: 0 the centres' shifts, 1 the shapes
  uvec2 shapes;     // Uints[5 n]: each particle's ellipsoid, its shape matrix and centre shift (band_ellipsoids); 0: none
  uvec2 marks;      // Uints[(n + 31) / 32]: a bit per entry, 1: a blob, not a particle (no shape, no neighbour); 0: none
} pc;

// Region k of `words` 32-bit words from `base`, as its own address, so that
// no array index reaches 4 GB past its reference: on the H200's driver such
// offsets went wrong (95.7M of 100M particles misclassified when the
// regions were indexed from the buffer's start).
uvec2 region(uvec2 base, uint k, uint words) {
  uint high, low, carry;
  umulExtended(k * words, 4u, high, low);  // k * words < 2^32: at most 5 x 2^29
  uint address = uaddCarry(base.x, low, carry);
  return uvec2(address, base.y + high + carry);
}

// The table, by slot: the voxel key (kEmpty where free; unused when dense),
// its particle count, its first place in the lists (band_scatter moves it
// to the end), 1 when L1, 1 when a selected L2 (a separate word: the L2
// pass writes it while reading neighbours' L1 marks).
#define KEY(s) Uints(pc.table).v[s]
#define COUNT(s) Uints(region(pc.table, 1u, pc.mask + 1u)).v[s]
#define START(s) Uints(region(pc.table, 2u, pc.mask + 1u)).v[s]
#define L1MARK(s) Uints(region(pc.table, 3u, pc.mask + 1u)).v[s]
#define L2MARK(s) Uints(region(pc.table, 4u, pc.mask + 1u)).v[s]
// By particle: its slot; the lists (particles voxel by voxel); the occupied
// slots (first Params.voxels); its io::BandLayer; its blob (kEmpty: none).
#define SLOT(i) Uints(pc.particles).v[i]
#define LIST(k) Uints(region(pc.particles, 1u, pc.n)).v[k]
#define VOXEL(k) Uints(region(pc.particles, 2u, pc.n)).v[k]
#define LAYER(i) Uints(region(pc.particles, 3u, pc.n)).v[i]
#define BLOB_OF(i) Uints(region(pc.particles, 4u, pc.n)).v[i]

const uint kEmpty = 0xffffffffu;

// The workgroup's place in a pass that covers `count` items in rounds of
// gl_NumWorkGroups.x * 256 (uniform per workgroup, so barriers are legal).
uint first_item() { return gl_WorkGroupID.x * 256u; }
uint round_stride() { return gl_NumWorkGroups.x * 256u; }

uint hash_key(uint k) {
  k ^= k >> 16;
  k *= 0x7feb352du;
  k ^= k >> 15;
  k *= 0x846ca68bu;
  k ^= k >> 16;
  return k;
}

// The slot holding voxel `key`, or kEmpty.
uint find_slot(uint key, Params g) {
  if (g.dense != 0u) return COUNT(key) != 0u ? key : kEmpty;
  uint s = hash_key(key) & pc.mask;
  for (;;) {
    uint k = KEY(s);
    if (k == key) return s;
    if (k == kEmpty) return kEmpty;
    s = (s + 1u) & pc.mask;
  }
}

vec3 particle(uint i) {
  Floats f = Floats(pc.xyz);
  return vec3(f.v[3u * i], f.v[3u * i + 1u], f.v[3u * i + 2u]);
}

// Cell coordinates (1 .. dims - 2) of position p, as the CPU computes them.
uvec3 cell_of(vec3 p, Params g) {
  uvec3 c;
  for (int a = 0; a < 3; ++a) {
    precise float cell = isinf(p[a]) || isnan(p[a]) ? 0.0 : (p[a] - g.origin[a]) * pc.inverse;
    // NaN (a degenerate box) to the first voxel, as the CPU does (clamp of NaN is undefined).
    c[a] = 1u + uint(cell > 0.0 ? min(cell, g.last_cell[a]) : 0.0);
  }
  return c;
}

uint key_of(uvec3 c, Params g) { return (c.x * g.dims[1] + c.y) * g.dims[2] + c.z; }

// The key of occupied slot s.
uint key_of_slot(uint s, Params g) { return g.dense != 0u ? s : KEY(s); }

uvec3 cell_of_key(uint key, Params g) {
  uint yz = g.dims[1] * g.dims[2];
  return uvec3(key / yz, (key / g.dims[2]) % g.dims[1], key % g.dims[2]);
}

// The slot of the voxel at c + d (c: an occupied cell, so c + d exists).
uint neighbour_slot(uvec3 c, ivec3 d, Params g) {
  return find_slot(key_of(uvec3(ivec3(c) + d), g), g);
}
