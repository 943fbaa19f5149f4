#version 460
// GPU decode of Quantized16 chunks (io/gpu_decode_plan.h has the plan, io
// codec.h the planes): one workgroup per tile of 2048 particles of a chunk,
// 8 per thread, in two passes.
//
// Pass 0 sums each tile's planes: the escape codes it holds and the sum of
// its other bytes, per plane. Pass 1 gives each tile what came before it in
// its chunk: the escapes used earlier (the earlier tiles' codes count them,
// and the workgroup sums their bytes from the list) and each plane's byte
// sum so far, hence the Morton code and the
// attribute value before the tile (a delta is the sum of its bytes
// shifted, so sums of deltas are sums of plane sums). Then each thread
// reads its 8 values of every plane (stored: 8 bytes; packed: one group of
// `width` bytes, spread), a workgroup scan of the escape codes found gives
// it its place in the escape lists, and a scan of the deltas' sums gives
// each particle its code and value. Writes what io::decode_chunk
// writes, bit for bit: x | y << 16 | z << 32 | lod << 48 per particle and
// the colour attribute's 16-bit values.
//
// Split positions (format 3.0, flag SPLIT): planes 0-1 hold the codes' low
// 16 bits as they are (flag FINE; without it every code's low bits are
// COARSE_FILL) and planes 2-5 bytes 0-3 of the deltas of their high 32.
//
// A packed plane whose escape codes disagree with its stored escape count
// (a corrupt file whose checksum was not checked) sets its chunk's error
// word; reads stay inside the encoded area whatever the bytes say (the plan
// checked every offset and size on the CPU).
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_16bit_storage : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

const uint T = 256;        // threads
const uint PER = 8;        // particles per thread: one packed group
const uint TILE = T * PER;
const uint PLANES = 10;    // io::kGpuPlanes

layout(local_size_x = 256) in;

struct Plane {
  uint offset;    // byte offset (packed: of its width byte)
  uint escapes;   // packed: byte offset of its escape list
  uint count;     // packed: escapes stored
  uint width;     // 0: stored; 1..7: packed
};
struct ChunkPlan {
  uint first;
  uint count;
  uint flags;       // io::kGpuWithAttribute, kGpuSplit, kGpuFine
  uint first_tile;
  Plane planes[PLANES];
};
const uint WITH_ATTRIBUTE = 1, SPLIT = 2, FINE = 4;
const uint COARSE_FILL = 0xE000u;  // io::kCoarseFill

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Words { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Plans { ChunkPlan c[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) writeonly buffer Particles { uvec2 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 2) writeonly buffer Values { uint16_t v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer Errors { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer TileChunks { uint v[]; };
// Per tile, PLANES words each: escape codes, the sum of the other bytes
// (pass 0).
layout(buffer_reference, std430, buffer_reference_align = 4) buffer TileSums { uint v[]; };

layout(push_constant) uniform Push {
  uvec2 encoded;    // Words: the encoded area (record, inflated planes, padding)
  uvec2 plans;      // Plans
  uvec2 particles;  // Particles: the frame's decoded particles
  uvec2 values;     // Values: the colour attribute (chunks with attribute = 1)
  uvec2 errors;     // Errors: one word per chunk, written only on error
  uvec2 tile_chunks;  // TileChunks: each tile's chunk
  uvec2 tile_sums;    // TileSums: 3 x PLANES words per tile
  uint tile_base;   // workgroup g decodes tile tile_base + g
  uint pass;        // 0: sum the tiles; 1: decode them
} pc;

// Workgroup totals per plane: escape codes, other bytes, escapes' bytes.
const uint COUNTS = 0, SUMS = 1, ESCAPES = 2;
shared uint totals[3][PLANES];

// Adds v over the workgroup into totals[which][p] (zeroed by clear_totals,
// read after a barrier).
void add(uint which, uint p, uint v) {
  const uint s = subgroupAdd(v);
  if (subgroupElect()) atomicAdd(totals[which][p], s);
}

void clear_totals() {
  const uint t = gl_LocalInvocationID.x;
  if (t < PLANES) {
    totals[COUNTS][t] = 0;
    totals[SUMS][t] = 0;
    totals[ESCAPES][t] = 0;
  }
  barrier();
}

// Exclusive sums over the workgroup: a subgroup scan, then each subgroup's
// total from shared memory (one barrier pair, where a Hillis-Steele scan
// over 256 threads takes eight). context.cpp requires subgroups of at
// least 4 lanes. Called in uniform control flow.
const uint WORDS = 5;      // the most words one scan carries
shared uint partial[T / 4][WORDS];

void exclusive_sums(inout uint v[WORDS], uint n, out uint total[WORDS]) {
  for (uint k = 0; k < n; ++k) {
    const uint inclusive = subgroupInclusiveAdd(v[k]);
    if (gl_SubgroupInvocationID == gl_SubgroupSize - 1) partial[gl_SubgroupID][k] = inclusive;
    v[k] = inclusive - v[k];
  }
  barrier();
  for (uint k = 0; k < n; ++k) {
    uint before = 0, all = 0;
    for (uint g = 0; g < gl_NumSubgroups; ++g) {
      const uint x = partial[g][k];
      before += g < gl_SubgroupID ? x : 0u;
      all += x;
    }
    v[k] += before;
    total[k] = all;
  }
  barrier();  // everyone has read before the next scan writes
}

// 8 bytes at byte offset `at`, little-endian (the area is padded behind).
uint64_t load8(Words w, uint at) {
  const uint i = at >> 2, s = (at & 3u) * 8u;
  const uint64_t lo = uint64_t(w.v[i]) | (uint64_t(w.v[i + 1]) << 32);
  return s == 0 ? lo : (lo >> s) | (uint64_t(w.v[i + 2]) << (64 - s));
}

uint load_byte(Words w, uint at) { return (w.v[at >> 2] >> ((at & 3u) * 8u)) & 0xffu; }

// The low `m` bytes of v (m in 0..8).
uint64_t keep_bytes(uint64_t v, uint m) { return m >= 8 ? v : v & ((uint64_t(1) << (8 * m)) - 1); }

// Gathers bits 0, 3, ..., 27 of v into bits 0..9.
uint compact10(uint v) {
  v &= 0x09249249u;
  v = (v ^ (v >> 2)) & 0x030c30c3u;
  v = (v ^ (v >> 4)) & 0x0300f00fu;
  v = (v ^ (v >> 8)) & 0xff0000ffu;
  return (v ^ (v >> 16)) & 0x3ffu;
}

// A 48-bit Morton code's x, y, z (io/src/morton.h) in 32-bit operations:
// bits 0..29 of the low word hold 10 bits of each axis, bits 30 and 31 the
// 11th of x and y, the high word the rest.
uvec3 morton_decode(uint64_t code) {
  const uint lo = uint(code), hi = uint(code >> 32);
  return uvec3(compact10(lo) | (((lo >> 30) & 1u) << 10) | (compact10(hi >> 1) << 11),
               compact10(lo >> 1) | ((lo >> 31) << 10) | (compact10(hi >> 2) << 11),
               compact10(lo >> 2) | (compact10(hi) << 10));
}

// This thread's 8 raw values of plane p (escape codes unresolved) and how
// many escape codes are among its first m.
uint64_t raw_values(Words w, Plane p, uint i0, uint m, out uint codes) {
  codes = 0;
  if (m == 0) return 0;
  if (p.width == 0) return keep_bytes(load8(w, p.offset + i0), m);
  const uint width = p.width, code = (1u << width) - 1u;
  const uint64_t bits = load8(w, p.offset + 1 + (i0 / PER) * width);
  uint64_t v = 0;
  for (uint j = 0; j < PER; ++j) {
    const uint value = uint(bits >> (j * width)) & code;
    v |= uint64_t(value) << (8 * j);
    codes += (j < m && value == code) ? 1u : 0u;
  }
  return keep_bytes(v, m);
}

// Replaces plane p's escape codes among the first m values by escapes
// from index `k` on (never past the plane's list).
uint64_t resolve_escapes(Words w, Plane p, uint64_t v, uint m, uint k) {
  if (p.width == 0) return v;
  const uint code = (1u << p.width) - 1u;
  for (uint j = 0; j < m; ++j) {
    if (uint(v >> (8 * j)) % 256u != code) continue;
    if (k < p.count) v = (v & ~(uint64_t(0xff) << (8 * j))) | (uint64_t(load_byte(w, p.escapes + k)) << (8 * j));
    ++k;
  }
  return v;
}

uint half16(uint v, uint h) { return (v >> (16 * h)) & 0xffffu; }

// The sum of the first m bytes of v that are not `code` (code > 255: all).
uint byte_sum(uint64_t v, uint m, uint code) {
  uint sum = 0;
  for (uint j = 0; j < m; ++j) {
    const uint b = uint(v >> (8 * j)) & 0xffu;
    sum += b != code ? b : 0u;
  }
  return sum;
}

uint escape_code(Plane p) { return p.width == 0 ? 256u : (1u << p.width) - 1u; }

void main() {
  const uint tile = pc.tile_base + gl_WorkGroupID.x;
  const uint chunk = TileChunks(pc.tile_chunks).v[tile];
  const ChunkPlan c = Plans(pc.plans).c[chunk];
  Words w = Words(pc.encoded);
  TileSums sums = TileSums(pc.tile_sums);
  const uint t = gl_LocalInvocationID.x;
  const bool colour = (c.flags & WITH_ATTRIBUTE) != 0;
  const bool split = (c.flags & SPLIT) != 0, fine = (c.flags & FINE) != 0;
  const uint planes = colour ? PLANES : 8;
  const uint first_plane = split && !fine ? 2u : 0u;  // planes 0-1 unused: no fine part
  const uint base = (tile - c.first_tile) * TILE;
  const uint i0 = base + t * PER;
  const uint m = i0 < c.count ? min(PER, c.count - i0) : 0;
  clear_totals();

  if (pc.pass == 0) {
    for (uint p = first_plane; p < planes; ++p) {
      uint found = 0;
      const uint64_t v = raw_values(w, c.planes[p], i0, m, found);
      add(COUNTS, p, found);
      add(SUMS, p, byte_sum(v, m, escape_code(c.planes[p])));
    }
    barrier();
    if (t < PLANES) {
      sums.v[tile * 2 * PLANES + t] = totals[COUNTS][t];
      sums.v[tile * 2 * PLANES + PLANES + t] = totals[SUMS][t];
    }
    return;
  }

  // What the chunk's earlier tiles hold: escape codes and other bytes; a
  // thread per word (a chunk has few tiles: 16 at the encoder's default of
  // 32768 particles).
  if (t < 2 * PLANES) {
    uint sum = 0;
    for (uint s = c.first_tile; s < tile; ++s) sum += sums.v[s * 2 * PLANES + t];
    totals[t / PLANES][t % PLANES] = sum;
  }
  barrier();
  uint escapes_before[PLANES];  // escapes used by earlier tiles, per plane
  for (uint p = 0; p < PLANES; ++p) escapes_before[p] = totals[COUNTS][p];
  // Their bytes: the first escapes_before of each list, summed here (a few
  // loads a thread: escapes are rare) rather than in a pass of their own.
  for (uint p = first_plane; p < planes; ++p) {
    const Plane plane = c.planes[p];
    if (plane.width == 0) continue;
    const uint end = min(escapes_before[p], plane.count);
    uint sum = 0;
    for (uint i = t; i < end; i += T) sum += load_byte(w, plane.escapes + i);
    add(ESCAPES, p, sum);
  }
  barrier();

  uint64_t code_before = 0;  // the Morton code before this tile
  uint value_before = 0;     // the attribute value before this tile
  const uint first_code_plane = split ? 2u : 0u;  // split: the low 16 bits are not deltas
  for (uint p = first_plane; p < planes; ++p) {
    const uint bytes = totals[SUMS][p] + totals[ESCAPES][p];
    if (p >= first_code_plane && p < 6) code_before += uint64_t(bytes) << (8 * p);
    if (p >= 8) value_before += bytes << (8 * (p - 8));
  }

  Particles out_particles = Particles(pc.particles);
  Values out_values = Values(pc.values);

  // Raw values and escape codes per plane; counts (at most 2048 a tile)
  // two to a word.
  uint64_t raw[PLANES];
  uint words[WORDS], totals_of[WORDS];
  for (uint k = 0; k < WORDS; ++k) words[k] = 0;
  for (uint p = 0; p < PLANES; ++p) {
    uint found = 0;
    raw[p] = p >= first_plane && p < planes ? raw_values(w, c.planes[p], i0, m, found) : 0;
    words[p / 2] |= found << (16 * (p % 2));
  }
  exclusive_sums(words, 5, totals_of);
  for (uint p = first_plane; p < planes; ++p) {
    const uint k = escapes_before[p] + half16(words[p / 2], p % 2);
    raw[p] = resolve_escapes(w, c.planes[p], raw[p], m, k);
    escapes_before[p] += half16(totals_of[p / 2], p % 2);
  }

  // Local running sums of the 8 deltas, then the workgroup's: a Morton
  // delta's sum is carried as three 16-bit pieces (a tile's sum of each
  // fits in 32 bits), recombined in 64 bits.
  uint64_t codes_local[PER];
  uint values_local[PER];
  uint64_t code_sum = 0;
  uint value_sum = 0;
  uint piece[3] = uint[3](0, 0, 0);
  for (uint j = 0; j < PER; ++j) {
    uint64_t delta = 0;
    for (uint q = first_code_plane / 2; q < 3; ++q) {
      const uint d = uint((raw[2 * q] >> (8 * j)) & 0xffUL) | (uint((raw[2 * q + 1] >> (8 * j)) & 0xffUL) << 8);
      piece[q] += d;
      delta |= uint64_t(d) << (16 * q);
    }
    code_sum += delta;
    codes_local[j] = code_sum;
    value_sum += uint((raw[8] >> (8 * j)) & 0xffUL) | (uint((raw[9] >> (8 * j)) & 0xffUL) << 8);
    values_local[j] = value_sum;
  }
  words[0] = piece[0];
  words[1] = piece[1];
  words[2] = piece[2];
  words[3] = value_sum;
  exclusive_sums(words, 4, totals_of);
  const uint64_t codes_before = uint64_t(words[0]) + (uint64_t(words[1]) << 16) + (uint64_t(words[2]) << 32);
  for (uint j = 0; j < m; ++j) {
    uint64_t code = (code_before + codes_before + codes_local[j]) & 0xffffffffffffUL;
    if (split) {
      const uint low = fine ? uint((raw[0] >> (8 * j)) & 0xffUL) | (uint((raw[1] >> (8 * j)) & 0xffUL) << 8) : COARSE_FILL;
      code = (code & 0xffffffff0000UL) | uint64_t(low);
    }
    const uint lod = uint((raw[6] >> (8 * j)) & 0xffUL) | (uint((raw[7] >> (8 * j)) & 0xffUL) << 8);
    const uvec3 xyz = morton_decode(code);
    out_particles.v[c.first + i0 + j] = uvec2(xyz.x | (xyz.y << 16), xyz.z | (lod << 16));
    if (colour) {
      out_values.v[c.first + i0 + j] = uint16_t((value_before + words[3] + values_local[j]) & 0xffffu);
    }
  }

  // The chunk's last tile: every escape code must have had its escape.
  if (t == 0 && base + TILE >= c.count) {
    bool bad = false;
    for (uint p = first_plane; p < planes; ++p) bad = bad || (c.planes[p].width != 0 && escapes_before[p] != c.planes[p].count);
    if (bad) Errors(pc.errors).v[chunk] = 1;
  }
}
