// The Layered Neighborhood Method on a voxel grid: particles sorted by voxel;
// on a dense grid every cell decided from its 26 neighbours by bit
// operations over the cells, on a sparse one (occupied voxels in a hash
// table) every voxel from its neighbours' lookups, in parallel.
#include "sluice/io/narrow_band.h"

#include "sluice/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/global_control.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <memory>
#include <stdexcept>

namespace sluice::io {
namespace {

constexpr int64_t kAxisCells = int64_t(1) << 20;  // per axis; keys hold 21 bits each

struct Box {
  float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
  float hi[3] = {std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest(),
                 std::numeric_limits<float>::lowest()};
  void join(const Box& o) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], o.lo[a]), hi[a] = std::max(hi[a], o.hi[a]);
  }
};

// Four lanes for GCC's (and Clang's) vector extensions, SIMD where the
// target has it. The loops over particles below go four particles at a
// time, their twelve coordinates in three vectors (GCC leaves the plain
// loops scalar): lane l of vector m holds axis (4m + l) % 3.
using Float4 = float __attribute__((vector_size(16)));
using Int4 = int32_t __attribute__((vector_size(16)));

Float4 axis_lanes(const float (&axis)[3], size_t m) {
  return Float4{axis[(4 * m) % 3], axis[(4 * m + 1) % 3], axis[(4 * m + 2) % 3], axis[(4 * m + 3) % 3]};
}

Float4 load(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// std::isfinite, lane by lane (a mask).
Int4 finite(Float4 v) {
  const Float4 infinity = Float4{} + std::numeric_limits<float>::infinity();
  return std::bit_cast<Float4>(std::bit_cast<Int4>(v) & 0x7fffffff) < infinity;
}

// The box of the finite coordinates of particles begin .. end-1. Lanes take
// their minima in another order than one loop would: only the sign of a
// zero bound can differ, which gives the same grid.
Box bounds(std::span<const float> xyz, size_t begin, size_t end) {
  Box b;
  const Float4 lowest = Float4{} + std::numeric_limits<float>::lowest(), highest = -lowest;
  Float4 lo[3] = {highest, highest, highest}, hi[3] = {lowest, lowest, lowest};
  size_t i = begin;
  for (; i + 4 <= end; i += 4) {
    for (size_t m = 0; m < 3; ++m) {
      const Float4 v = load(&xyz[3 * i + 4 * m]);
      const Int4 counted = finite(v);
      lo[m] = (counted & (v < lo[m])) ? v : lo[m];
      hi[m] = (counted & (hi[m] < v)) ? v : hi[m];
    }
  }
  for (size_t m = 0; m < 3; ++m) {
    for (size_t lane = 0; lane < 4; ++lane) {
      const size_t a = (4 * m + lane) % 3;
      b.lo[a] = std::min(b.lo[a], lo[m][lane]), b.hi[a] = std::max(b.hi[a], hi[m][lane]);
    }
  }
  for (; i < end; ++i) {
    for (size_t a = 0; a < 3; ++a) {
      const float v = xyz[3 * i + a];
      if (!std::isfinite(v)) continue;
      b.lo[a] = std::min(b.lo[a], v), b.hi[a] = std::max(b.hi[a], v);
    }
  }
  return b;
}

Box bounds(std::span<const float> xyz) {
  const size_t n = xyz.size() / 3;
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 16384), Box{},
      [&](const tbb::blocked_range<size_t>& r, Box b) {
        b.join(bounds(xyz, r.begin(), r.end()));
        return b;
      },
      [](Box a, const Box& b) {
        a.join(b);
        return a;
      });
}

// One bit per cell of a dense grid.
using CellBits = std::vector<uint64_t>;

bool has(const CellBits& bits, uint64_t c) { return (bits[c / 64] >> (c % 64)) & 1; }

// The 64 bits of `bits` from bit `first` on (zeros outside).
uint64_t bits_from(const CellBits& bits, int64_t first) {
  const auto word = [&](int64_t w) { return w >= 0 && w < int64_t(bits.size()) ? bits[size_t(w)] : uint64_t(0); };
  const int64_t w = first >> 6, shift = first & 63;
  return shift == 0 ? word(w) : (word(w) >> shift) | (word(w + 1) << (64 - shift));
}

// Word by word, in parallel: out[w] = f(w).
template <class F>
CellBits each_word(size_t words, F&& f) {
  CellBits out(words);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, words, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t w = r.begin(); w < r.end(); ++w) out[w] = f(w);
  });
  return out;
}

// Bit c of the result: bits c - step, c and c + step of `bits`, or-ed.
CellBits spread(const CellBits& bits, int64_t step) {
  return each_word(bits.size(), [&](size_t w) {
    const int64_t first = int64_t(64 * w);
    return bits[w] | bits_from(bits, first - step) | bits_from(bits, first + step);
  });
}

// Occupied voxels: the particles sorted by voxel, each voxel a run of them.
// Where the particles' box holds few enough cells (a fluid body, not spray
// flung far away), a dense array maps every cell to its voxel and the sort
// is a counting sort over cells; otherwise the keys are sorted and an
// open-addressing table finds voxels by key. Both give the same voxels in
// the same (x, y, z) order, particles in index order within a voxel.
class VoxelGrid {
 public:
  VoxelGrid(std::span<const float> xyz, float side) : side_(side) {
    const size_t n = xyz.size() / 3;
    box_ = bounds(xyz);
    uint64_t cells = 1;
    // Float operations only, each rounded on its own (this file builds
    // without contraction into FMA): the GPU classifier (render's
    // band_grid.comp and band.glsl) repeats them and must get the same voxels.
    inverse_side_ = 1.0f / side_;
    for (int a = 0; a < 3; ++a) {
      // Coordinates 1 .. dims-2: cell 0 and the last are the outside.
      const float extent = box_.hi[a] >= box_.lo[a] ? box_.hi[a] - box_.lo[a] : 0.0f;
      float extent_cells = std::floor(extent * inverse_side_ + 0.25f);
      // A side so small that its inverse overflows, on a flat axis: 0 x inf
      // (found by fuzz_vtk_import, tests/data/fuzz/vtk/flat_axis_overflowing_voxel.vtk).
      if (std::isnan(extent_cells)) extent_cells = 0.0f;
      dims_[a] = int64_t(std::min(extent_cells + 3.0f, float(kAxisCells)));
      cells *= uint64_t(dims_[a]);
      origin_[a] = box_.lo[a] - 0.25f * side_;
      last_cell_[a] = float(dims_[a] - 3);
    }
    if (cells <= std::max<uint64_t>(8 * uint64_t(n), uint64_t(1) << 20) && cells < kEmpty) {
      build_dense(xyz, cells);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            if (dx != 0 || dy != 0 || dz != 0) offsets_.push_back((dx * dims_[1] + dy) * dims_[2] + dz);
          }
    } else {
      build_sparse(xyz);
    }
  }

  struct Voxel {
    uint64_t key;
    uint32_t first;  // into particles()
    uint32_t count;
  };

  size_t size() const { return voxels_.size(); }
  const Voxel& voxel(size_t v) const { return voxels_[v]; }
  // Particle indices, voxel by voxel.
  uint32_t particle(size_t k) const { return order_[k]; }

  // Dense grids: calls f for the 26 neighbours of voxel v straight from the
  // cell array (an occupied cell is never on the outside layer, so every
  // neighbour cell exists) and returns true; sparse grids: returns false.
  template <class F>
  bool each_dense_neighbour(size_t v, F& f) const {
    if (cell_voxel_.empty()) return false;
    const int64_t centre = cell_of(voxels_[v].key);
    for (const int64_t offset : offsets_) {
      const uint32_t w = cell_voxel_[size_t(centre + offset)];
      if (!f(w == kEmpty ? int64_t(-1) : int64_t(w))) break;
    }
    return true;
  }

  // Dense grids: a cell array over the box, every particle's cell kept.
  bool dense() const { return !cell_voxel_.empty(); }
  uint32_t cell_of_particle(size_t i) const { return particle_cell_[i]; }
  uint32_t cell_of_voxel(size_t v) const { return cell_of(voxels_[v].key); }
  uint32_t voxel_of_cell(uint32_t c) const { return cell_voxel_[c]; }

  // Dense grids: the cells whose voxel satisfies pred.
  template <class P>
  CellBits cells_where(P&& pred) const {
    return each_word((cell_voxel_.size() + 63) / 64, [&](size_t w) {
      uint64_t word = 0;
      for (size_t c = 64 * w; c < std::min(64 * w + 64, cell_voxel_.size()); ++c) {
        const uint32_t v = cell_voxel_[c];
        if (v != kEmpty && pred(voxels_[v])) word |= uint64_t(1) << (c % 64);
      }
      return word;
    });
  }

  // Dense grids: the cells with a set cell among themselves and their 26
  // neighbours, three separable passes over words instead of 26 lookups per
  // voxel. The offsets wrap across rows only at the outside layer, so the
  // result is exact at every cell that holds a voxel.
  CellBits around(const CellBits& bits) const {
    return spread(spread(spread(bits, 1), dims_[2]), dims_[1] * dims_[2]);
  }

  // The voxel at key + (dx, dy, dz), or -1 when empty or outside.
  int64_t neighbour(uint64_t key, int dx, int dy, int dz) const {
    const int64_t x = int64_t(key >> 42) + dx, y = int64_t((key >> 21) & 0x1FFFFF) + dy,
                  z = int64_t(key & 0x1FFFFF) + dz;
    if (!cell_voxel_.empty()) {
      if (x < 0 || y < 0 || z < 0 || x >= dims_[0] || y >= dims_[1] || z >= dims_[2]) return -1;
      const uint32_t v = cell_voxel_[size_t((x * dims_[1] + y) * dims_[2] + z)];
      return v == kEmpty ? -1 : int64_t(v);
    }
    if (x < 0 || y < 0 || z < 0 || x > kAxisCells || y > kAxisCells || z > kAxisCells) return -1;
    return find(pack(x, y, z));
  }

 private:
  static constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();
  static constexpr uint32_t kBucketCells = 4096;  // cells per bucket of the counting sort's first pass

  struct CellParticle {
    uint32_t cell;
    uint32_t particle;
  };

  static uint64_t pack(int64_t x, int64_t y, int64_t z) { return (uint64_t(x) << 42) | (uint64_t(y) << 21) | uint64_t(z); }
  // Dense grids: a key's cell in the cell array, and back.
  uint32_t cell_of(uint64_t key) const {
    return uint32_t((int64_t(key >> 42) * dims_[1] + int64_t((key >> 21) & 0x1FFFFF)) * dims_[2] + int64_t(key & 0x1FFFFF));
  }
  uint64_t key_of_cell(uint64_t c) const {
    const uint64_t z = c % uint64_t(dims_[2]), y = c / uint64_t(dims_[2]) % uint64_t(dims_[1]),
                   x = c / (uint64_t(dims_[2]) * uint64_t(dims_[1]));
    return pack(int64_t(x), int64_t(y), int64_t(z));
  }
  // The key of the next cell in the cell array (z fastest, then y, then x),
  // without key_of_cell's divisions.
  uint64_t next_cell_key(uint64_t key) const {
    constexpr uint64_t kField = 0x1FFFFF;
    if ((key & kField) + 1 < uint64_t(dims_[2])) return key + 1;
    key &= ~kField;  // z = 0
    if (((key >> 21) & kField) + 1 < uint64_t(dims_[1])) return key + (uint64_t(1) << 21);
    return (key & ~(kField << 21)) + (uint64_t(1) << 42);  // y = 0, the next x
  }
  static uint64_t hash(uint64_t k) {
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    return k;
  }

  // Counting sort over the box's cells, in two stable passes that run in
  // parallel without atomics: particles into buckets of 2^kBucketBits
  // consecutive cells (each of T index ranges counts and then scatters its
  // own particles, in index order), then each bucket sorted by cell on its
  // own. The order is the same on any number of threads: particles in cell
  // order, index order within a cell. Each particle travels with its cell,
  // so the bucket passes read their input in order instead of looking cells
  // up by particle index (a cache miss per particle on large frames).
  void build_dense(std::span<const float> xyz, uint64_t cells) {
    const size_t n = xyz.size() / 3;
    particle_cell_.resize(n);
    const std::span<const uint32_t> cell = particle_cell_;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16384), [&](const tbb::blocked_range<size_t>& r) {
      cells_of(xyz, r.begin(), r.end(), &particle_cell_[r.begin()]);
    });
    const size_t buckets = size_t((cells + kBucketCells - 1) / kBucketCells);
    const size_t ranges = std::clamp<size_t>(n / 65536, 1, 64);
    const auto range_begin = [&](size_t r) { return n * r / ranges; };
    // offset[r * buckets + b]: where range r's particles of bucket b go.
    std::vector<uint32_t> offset(ranges * buckets, 0);
    tbb::parallel_for(size_t(0), ranges, [&](size_t r) {
      uint32_t* count = &offset[r * buckets];
      for (size_t i = range_begin(r); i < range_begin(r + 1); ++i) ++count[cell[i] / kBucketCells];
    });
    std::vector<uint32_t> bucket_start(buckets + 1, 0);
    uint32_t total = 0;
    for (size_t b = 0; b < buckets; ++b) {
      bucket_start[b] = total;
      for (size_t r = 0; r < ranges; ++r) {
        const uint32_t c = offset[r * buckets + b];
        offset[r * buckets + b] = total;
        total += c;
      }
    }
    bucket_start[buckets] = total;
    const auto by_bucket = std::make_unique_for_overwrite<CellParticle[]>(n);
    tbb::parallel_for(size_t(0), ranges, [&](size_t r) {
      uint32_t* next = &offset[r * buckets];
      for (size_t i = range_begin(r); i < range_begin(r + 1); ++i) by_bucket[next[cell[i] / kBucketCells]++] = {cell[i], uint32_t(i)};
    });
    const auto bucket_particles = [&](size_t b) {
      return std::span<const CellParticle>(&by_bucket[bucket_start[b]], bucket_start[b + 1] - bucket_start[b]);
    };
    const auto bucket_cells = [&](size_t b) {
      return std::span<uint32_t>(cell_voxel_).subspan(b * kBucketCells, std::min<uint64_t>(kBucketCells, cells - b * kBucketCells));
    };
    // Particles per cell, held in cell_voxel_ until the voxels are numbered;
    // each bucket's occupied cells counted for that numbering.
    cell_voxel_.resize(cells);
    std::vector<uint32_t> occupied(buckets + 1, 0);
    tbb::parallel_for(size_t(0), buckets, [&](size_t b) {
      const std::span<uint32_t> count = bucket_cells(b);
      std::fill(count.begin(), count.end(), 0u);
      for (const CellParticle& p : bucket_particles(b)) ++count[p.cell % kBucketCells];
      occupied[b + 1] = uint32_t(count.size() - size_t(std::count(count.begin(), count.end(), 0u)));
    });
    for (size_t b = 0; b < buckets; ++b) occupied[b + 1] += occupied[b];
    voxels_.resize(occupied[buckets]);
    order_.resize(n);
    tbb::parallel_for(size_t(0), buckets, [&](size_t b) {
      const std::span<uint32_t> count_then_voxel = bucket_cells(b);
      uint32_t next[kBucketCells];  // where each cell's next particle goes
      uint32_t v = occupied[b], at = bucket_start[b];
      uint64_t key = key_of_cell(b * kBucketCells);
      for (size_t c = 0; c < count_then_voxel.size(); ++c, key = next_cell_key(key)) {
        const uint32_t count = count_then_voxel[c];
        next[c] = at;
        if (count == 0) {
          count_then_voxel[c] = kEmpty;
          continue;
        }
        voxels_[v] = {key, at, count};
        count_then_voxel[c] = v++;
        at += count;
      }
      for (const CellParticle& p : bucket_particles(b)) order_[next[p.cell % kBucketCells]++] = p.particle;
    });
  }

  void build_sparse(std::span<const float> xyz) {
    const size_t n = xyz.size() / 3;
    std::vector<std::pair<uint64_t, uint32_t>> keyed(n);  // (voxel key, particle)
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16384), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) keyed[i] = {key_of(xyz, i), uint32_t(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    order_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      order_[i] = keyed[i].second;
      if (i == 0 || keyed[i].first != keyed[i - 1].first) voxels_.push_back({keyed[i].first, uint32_t(i), 0});
      ++voxels_.back().count;
    }
    size_t capacity = 16;
    while (capacity < 2 * voxels_.size()) capacity *= 2;
    table_.assign(capacity, kEmpty);
    for (uint32_t v = 0; v < voxels_.size(); ++v) {
      size_t slot = hash(voxels_[v].key) & (capacity - 1);
      while (table_[slot] != kEmpty) slot = (slot + 1) & (capacity - 1);
      table_[slot] = v;
    }
  }

  // Voxel coordinates start at 1: voxel 0 of every axis is the outside. The
  // grid starts a quarter voxel below the lowest particle, so that particles
  // on a lattice of half the voxel side (a solver's first frame) never lie
  // on a voxel boundary, where rounding would decide their voxel.
  uint64_t key_of(std::span<const float> xyz, size_t i) const {
    int64_t c[3];
    for (int a = 0; a < 3; ++a) {
      const float v = xyz[3 * i + a];
      // >= 0 for a particle in the box, so truncation is floor; a
      // multiplication, not a division: this runs for every particle.
      const float cell = std::isfinite(v) ? (v - origin_[a]) * inverse_side_ : 0.0f;
      // NaN (a degenerate box: an infinite extent) goes to the first voxel, as
      // below-the-box does; converting NaN to an integer is undefined.
      c[a] = 1 + int64_t(cell > 0.0f ? std::min(cell, last_cell_[a]) : 0.0f);
    }
    return pack(c[0], c[1], c[2]);
  }

  // Dense grids: the cells of particles begin .. end-1, key_of's float
  // arithmetic four particles at a time (the costliest arithmetic of the
  // classification).
  void cells_of(std::span<const float> xyz, size_t begin, size_t end, uint32_t* cell) const {
    const Float4 origin[3] = {axis_lanes(origin_, 0), axis_lanes(origin_, 1), axis_lanes(origin_, 2)};
    const Float4 last_cell[3] = {axis_lanes(last_cell_, 0), axis_lanes(last_cell_, 1), axis_lanes(last_cell_, 2)};
    const Float4 zero{};
    size_t i = begin;
    for (; i + 4 <= end; i += 4) {
      int32_t c[12];
      for (size_t m = 0; m < 3; ++m) {
        const Float4 v = load(&xyz[3 * i + 4 * m]);
        Float4 t = finite(v) ? (v - origin[m]) * inverse_side_ : zero;
        t = zero < t ? t : zero;              // NaN (a degenerate box) to 0, as key_of does
        t = last_cell[m] < t ? last_cell[m] : t;
        const Int4 cm = __builtin_convertvector(t, Int4) + 1;
        std::memcpy(&c[4 * m], &cm, sizeof cm);
      }
      for (size_t j = 0; j < 4; ++j) cell[i - begin + j] = cell_of(pack(c[3 * j], c[3 * j + 1], c[3 * j + 2]));
    }
    for (; i < end; ++i) cell[i - begin] = cell_of(key_of(xyz, i));
  }

  int64_t find(uint64_t key) const {
    size_t slot = hash(key) & (table_.size() - 1);
    while (table_[slot] != kEmpty) {
      if (voxels_[table_[slot]].key == key) return table_[slot];
      slot = (slot + 1) & (table_.size() - 1);
    }
    return -1;
  }

  float side_;
  Box box_;
  int64_t dims_[3] = {1, 1, 1};         // cells per axis, the outside layer included
  float origin_[3] = {0, 0, 0};         // a quarter voxel below the box
  float last_cell_[3] = {0, 0, 0};      // the highest cell index a particle may get, per axis
  float inverse_side_ = 1;
  std::vector<uint32_t> order_;         // particle indices, sorted by voxel
  std::vector<Voxel> voxels_;
  std::vector<uint32_t> table_;         // sparse: voxel by key hash
  std::vector<uint32_t> cell_voxel_;    // dense: voxel by cell, kEmpty where none
  std::vector<uint32_t> particle_cell_;  // dense: each particle's cell
  std::vector<int64_t> offsets_;        // dense: the 26 neighbours' cells, relative
};

// Calls f(w) for the 26 voxels around voxel v (w = -1: empty or outside)
// until f returns false.
template <class F>
void for_each_neighbour(const VoxelGrid& grid, size_t v, F&& f) {
  if (grid.each_dense_neighbour(v, f)) return;
  const uint64_t key = grid.voxel(v).key;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        if (!f(grid.neighbour(key, dx, dy, dz))) return;
      }
}

float distance2(std::span<const float> xyz, size_t i, size_t j) {
  float d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const float d = xyz[3 * i + a] - xyz[3 * j + a];
    d2 += d * d;
  }
  return d2;
}

// The 26 neighbours of a voxel, faces first, then edges, then corners: the
// nearest are the likeliest to hold a particle within reach.
constexpr auto kNearestFirst = [] {
  std::array<std::array<int, 3>, 26> out{};
  size_t k = 0;
  for (int axes = 1; axes <= 3; ++axes)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if ((dx != 0) + (dy != 0) + (dz != 0) == axes) out[k++] = {dx, dy, dz};
        }
  return out;
}();

// True when no other particle lies within `reach` of particle i, looked for
// in its voxel and the 26 around (reach <= the voxel side), the nearest
// voxels first.
bool alone(const VoxelGrid& grid, std::span<const float> xyz, size_t v, uint32_t i, float reach) {
  const float r2 = reach * reach;
  const auto none_near = [&](int64_t w) {
    if (w < 0) return true;
    const auto& vox = grid.voxel(size_t(w));
    for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) {
      const uint32_t j = grid.particle(k);
      if (j != i && distance2(xyz, i, j) < r2) return false;
    }
    return true;
  };
  if (!none_near(int64_t(v))) return false;
  const uint64_t key = grid.voxel(v).key;
  for (const auto& d : kNearestFirst) {
    if (!none_near(grid.neighbour(key, d[0], d[1], d[2]))) return false;
  }
  return true;
}

// |x_i - sum_j x_j W_ij| with normalized weights W over the 27 voxels
// around (the dissertation's asymmetry value).
float asymmetry(const VoxelGrid& grid, std::span<const float> xyz, size_t v, uint32_t i, float h) {
  const float support2 = 4 * h * h;
  double sum[3] = {0, 0, 0}, weights = 0;
  const auto add = [&](int64_t w) {
    if (w < 0) return true;
    const auto& vox = grid.voxel(size_t(w));
    for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) {
      const uint32_t j = grid.particle(k);
      const float q = distance2(xyz, i, j) / support2;
      if (q >= 1) continue;
      const double wgt = std::pow(1.0 - q, 3);
      for (int a = 0; a < 3; ++a) sum[a] += wgt * xyz[3 * size_t(j) + a];
      weights += wgt;
    }
    return true;
  };
  add(int64_t(v));
  for_each_neighbour(grid, v, add);
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = xyz[3 * size_t(i) + a] - sum[a] / weights;
    d2 += d * d;
  }
  return float(std::sqrt(d2));
}

// A voxel's kind: L1, selected L2, or neither (0).
constexpr uint8_t kL1 = 1, kSelectedL2 = 2;

BandLayer layer_of_kind(uint8_t kind) {
  return kind == kL1 ? BandLayer::L1 : kind == kSelectedL2 ? BandLayer::L2 : BandLayer::Interior;
}

// Sparse grids: L1 voxels have an empty or outside voxel among their 26
// neighbours; selected L2 voxels are next to an L1 voxel of at most n1
// particles.
std::vector<uint8_t> voxel_kinds_by_neighbours(const VoxelGrid& grid, double n1) {
  std::vector<uint8_t> kind(grid.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      bool l1 = false;
      for_each_neighbour(grid, v, [&](int64_t w) { return !(l1 = w < 0); });
      if (l1) kind[v] = kL1;
    }
  });
  // Selected L2 voxels go to a vector of their own: the pass reads the
  // neighbours' L1 marks, which must not change under it.
  std::vector<uint8_t> selected(grid.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      if (kind[v] == kL1) continue;
      for_each_neighbour(grid, v, [&](int64_t w) {
        selected[v] = w >= 0 && kind[size_t(w)] == kL1 && double(grid.voxel(size_t(w)).count) <= n1;
        return !selected[v];
      });
    }
  });
  for (size_t v = 0; v < grid.size(); ++v) {
    if (selected[v]) kind[v] = kSelectedL2;
  }
  return kind;
}

// Dense grids: the same kinds as voxel_kinds_by_neighbours, cell by cell.
struct CellKinds {
  CellBits l1, selected_l2;
  uint8_t at(uint64_t c) const { return has(l1, c) ? kL1 : has(selected_l2, c) ? kSelectedL2 : 0; }
};

CellKinds cell_kinds(const VoxelGrid& grid, double n1) {
  const CellBits occupied = grid.cells_where([](const VoxelGrid::Voxel&) { return true; });
  const CellBits few = grid.cells_where([&](const VoxelGrid::Voxel& v) { return double(v.count) <= n1; });
  const size_t words = occupied.size();
  CellKinds kinds;
  const CellBits near_empty = grid.around(each_word(words, [&](size_t w) { return ~occupied[w]; }));
  kinds.l1 = each_word(words, [&](size_t w) { return occupied[w] & near_empty[w]; });
  const CellBits near_few_l1 = grid.around(each_word(words, [&](size_t w) { return kinds.l1[w] & few[w]; }));
  kinds.selected_l2 = each_word(words, [&](size_t w) { return occupied[w] & ~kinds.l1[w] & near_few_l1[w]; });
  return kinds;
}

std::vector<uint8_t> voxel_kinds(const VoxelGrid& grid, const CellKinds& cells) {
  std::vector<uint8_t> kind(grid.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) kind[v] = cells.at(grid.cell_of_voxel(v));
  });
  return kind;
}

// Every particle's layer by its voxel's kind, in particle order: the writes
// go in order and the bits read fit in cache.
void layers_by_cell(const VoxelGrid& grid, const CellKinds& cells, std::vector<BandLayer>& layer) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, layer.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) layer[i] = layer_of_kind(cells.at(grid.cell_of_particle(i)));
  });
}

// Every particle's layer by its voxel's kind, voxel by voxel.
void layers_by_voxel(const VoxelGrid& grid, const std::vector<uint8_t>& kind, std::vector<BandLayer>& layer) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const auto& vox = grid.voxel(v);
      for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) layer[grid.particle(k)] = layer_of_kind(kind[v]);
    }
  });
}

// The tests particle by particle, over the voxels that need them: F2 by
// asymmetry in selected L2 voxels, and the isolated test in sparse voxels
// (a voxel of the dense fluid holds about (d/h)^3 particles), which makes
// spray and droplets surface whatever their voxel.
void test_particles(const VoxelGrid& grid, std::span<const float> xyz, const std::vector<uint8_t>& kind, F2Test f2,
                    float h, float reach, std::vector<BandLayer>& layer) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const auto& vox = grid.voxel(v);
      const bool test_f2 = kind[v] == kSelectedL2 && f2 == F2Test::Asymmetry, test_alone = vox.count <= 2;
      if (!test_f2 && !test_alone) continue;
      for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) {
        const uint32_t i = grid.particle(k);
        BandLayer l = layer_of_kind(kind[v]);
        if (test_f2 && !(asymmetry(grid, xyz, v, i, h) > 0.1f * h)) l = BandLayer::Interior;
        if (test_alone && alone(grid, xyz, v, i, reach)) l = BandLayer::Isolated;
        layer[i] = l;
      }
    }
  });
}

// Particles per layer, in blocks short enough for 32-bit counters (which
// the compiler vectorizes, unlike an increment indexed by the layer).
std::array<uint64_t, 4> count_layers(const std::vector<BandLayer>& layer) {
  constexpr size_t kBlock = size_t(1) << 16;
  std::array<uint64_t, 4> counts{};
  for (size_t begin = 0; begin < layer.size(); begin += kBlock) {
    uint32_t block[4] = {};
    for (size_t i = begin; i < std::min(layer.size(), begin + kBlock); ++i) {
      for (size_t l = 1; l < 4; ++l) block[l] += layer[i] == BandLayer(l);
    }
    for (size_t l = 1; l < 4; ++l) counts[l] += block[l];
  }
  counts[0] = layer.size() - counts[1] - counts[2] - counts[3];
  return counts;
}

// Per voxel: how many interior particles, and their positions summed in
// double in index order.
struct InteriorSums {
  std::vector<uint32_t> count;
  std::vector<std::array<double, 3>> sum;
  explicit InteriorSums(size_t voxels) : count(voxels, 0), sum(voxels, {0, 0, 0}) {}
};

// Voxel by voxel: reads each voxel's particles where they lie in memory.
InteriorSums interior_sums_by_voxel(const VoxelGrid& grid, std::span<const float> xyz, const std::vector<BandLayer>& layer) {
  InteriorSums out(grid.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const auto& vox = grid.voxel(v);
      for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) {
        const uint32_t i = grid.particle(k);
        if (layer[i] != BandLayer::Interior) continue;
        for (size_t a = 0; a < 3; ++a) out.sum[v][a] += xyz[3 * size_t(i) + a];
        ++out.count[v];
      }
    }
  });
  return out;
}

// Dense grids: the same sums in particle order, which reads positions in
// order instead of one cache miss per particle. Each task owns a slab of
// voxels and scans every particle's cell for its own, so every voxel is
// still summed by one task in index order; one slab per thread at work.
InteriorSums interior_sums_by_cell(const VoxelGrid& grid, std::span<const float> xyz, const std::vector<BandLayer>& layer) {
  InteriorSums out(grid.size());
  const size_t threads = std::min<size_t>(size_t(tbb::this_task_arena::max_concurrency()),
                                          tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  const size_t slabs = std::clamp<size_t>(threads, 1, grid.size());
  tbb::parallel_for(size_t(0), slabs, [&](size_t s) {
    const uint32_t lo = grid.cell_of_voxel(grid.size() * s / slabs), hi = grid.cell_of_voxel(grid.size() * (s + 1) / slabs - 1);
    for (size_t i = 0; i < layer.size(); ++i) {
      const uint32_t c = grid.cell_of_particle(i);
      if (c < lo || c > hi || layer[i] != BandLayer::Interior) continue;
      const uint32_t v = grid.voxel_of_cell(c);
      for (size_t a = 0; a < 3; ++a) out.sum[v][a] += xyz[3 * i + a];
      ++out.count[v];
    }
  });
  return out;
}

// One blob per voxel with interior particles, in voxel order (the grid's
// key order: spatially coherent); returns each voxel's blob (kNoBlob where
// none).
std::vector<uint32_t> make_blobs(const InteriorSums& interior, std::vector<VoxelBlob>& blobs) {
  const size_t voxels = interior.count.size();
  std::vector<uint32_t> blob_of_voxel(voxels, NarrowBand::kNoBlob);
  uint32_t next = 0;
  for (size_t v = 0; v < voxels; ++v) {
    if (interior.count[v] > 0) blob_of_voxel[v] = next++;
  }
  blobs.resize(next);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, voxels, 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      if (blob_of_voxel[v] == NarrowBand::kNoBlob) continue;
      VoxelBlob& b = blobs[blob_of_voxel[v]];
      b.count = interior.count[v];
      for (size_t a = 0; a < 3; ++a) b.centroid[a] = float(interior.sum[v][a] / interior.count[v]);
    }
  });
  return blob_of_voxel;
}

// Every interior particle's blob, its voxel's; surface particles none.
void assign_blobs(const VoxelGrid& grid, const std::vector<uint32_t>& blob_of_voxel, NarrowBand& out) {
  out.blob_of.assign(out.layer.size(), NarrowBand::kNoBlob);
  if (grid.dense()) {  // in particle order: the writes go in order
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.layer.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        if (out.layer[i] == BandLayer::Interior) out.blob_of[i] = blob_of_voxel[grid.voxel_of_cell(grid.cell_of_particle(i))];
      }
    });
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      if (blob_of_voxel[v] == NarrowBand::kNoBlob) continue;
      const auto& vox = grid.voxel(v);
      for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) {
        const uint32_t i = grid.particle(k);
        if (out.layer[i] == BandLayer::Interior) out.blob_of[i] = blob_of_voxel[v];
      }
    }
  });
}

// The interior's blobs; the sums are dropped before blob_of is allocated.
void gather_blobs(const VoxelGrid& grid, std::span<const float> xyz, NarrowBand& out) {
  const std::vector<uint32_t> blob_of_voxel =
      make_blobs(grid.dense() ? interior_sums_by_cell(grid, xyz, out.layer) : interior_sums_by_voxel(grid, xyz, out.layer), out.blobs);
  assign_blobs(grid, blob_of_voxel, out);
}

}  // namespace

NarrowBand classify_narrow_band(std::span<const float> xyz, const NarrowBandOptions& o) {
  if (!(o.diameter > 0)) throw Error({}, "classify_narrow_band: the particle diameter must be positive");
  const float h = o.diameter;
  NarrowBand out;
  out.voxel = o.voxel > 0 ? o.voxel : 2 * h;
  const size_t n = xyz.size() / 3;
  out.layer.assign(n, BandLayer::Interior);
  if (n == 0) return out;
  const VoxelGrid grid(xyz, out.voxel);
  out.voxels = grid.size();
  // n1 = (d/h)^3: fewer particles than that cannot hide what lies behind.
  const double n1 = std::pow(double(out.voxel) / h, 3);

  std::vector<uint8_t> kind;  // per voxel: kL1, kSelectedL2 or 0
  if (grid.dense()) {
    const CellKinds cells = cell_kinds(grid, n1);
    kind = voxel_kinds(grid, cells);
    layers_by_cell(grid, cells, out.layer);
  } else {
    kind = voxel_kinds_by_neighbours(grid, n1);
    layers_by_voxel(grid, kind, out.layer);
  }
  test_particles(grid, xyz, kind, o.f2, h, std::min(2 * h, out.voxel), out.layer);
  out.counts = count_layers(out.layer);
  if (o.blobs) gather_blobs(grid, xyz, out);
  for (const uint8_t k : kind) {
    out.l1_voxels += k == kL1;
    out.l2_voxels += k == kSelectedL2;
  }
  return out;
}

std::vector<bool> exact_narrow_band(std::span<const float> xyz, float diameter, int directions) {
  const size_t n = xyz.size() / 3;
  std::vector<bool> out(n, false);
  if (n == 0 || !(diameter > 0) || directions < 1) return out;
  const float h = diameter;
  // Voxels of side h: every particle within h of a point within h of
  // particle i lies in the 5x5x5 voxels around i's.
  const VoxelGrid grid(xyz, h);
  std::vector<std::array<float, 3>> dirs(static_cast<size_t>(directions));
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < directions; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / directions, r = std::sqrt(1.0 - z * z), phi = golden * k;
    dirs[size_t(k)] = {float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)};
  }
  std::vector<uint8_t> exposed(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint32_t> near;
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const auto& vox = grid.voxel(v);
      near.clear();
      for (int dx = -2; dx <= 2; ++dx)
        for (int dy = -2; dy <= 2; ++dy)
          for (int dz = -2; dz <= 2; ++dz) {
            const int64_t w = (dx | dy | dz) == 0 ? int64_t(v) : grid.neighbour(vox.key, dx, dy, dz);
            if (w < 0) continue;
            const auto& other = grid.voxel(size_t(w));
            for (uint32_t k = other.first; k < other.first + other.count; ++k) near.push_back(grid.particle(k));
          }
      for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) {
        const uint32_t i = grid.particle(k);
        for (const auto& d : dirs) {
          float p[3];
          for (int a = 0; a < 3; ++a) p[a] = xyz[3 * size_t(i) + a] + h * d[a];
          // Covered: strictly within h of another particle (a tolerance
          // keeps points exactly at distance h, the lattice's ties, out).
          const float covered2 = h * h * (1.0f - 1e-4f);
          bool covered = false;
          for (const uint32_t j : near) {
            if (j == i) continue;
            float d2 = 0;
            for (int a = 0; a < 3; ++a) {
              const float e = p[a] - xyz[3 * size_t(j) + a];
              d2 += e * e;
            }
            if (d2 < covered2) {
              covered = true;
              break;
            }
          }
          if (!covered) {
            exposed[i] = 1;
            break;
          }
        }
      }
    }
  });
  for (size_t i = 0; i < n; ++i) out[i] = exposed[i] != 0;
  return out;
}

std::vector<uint8_t> voxel_layers(std::span<const float> xyz, float voxel) {
  const size_t n = xyz.size() / 3;
  std::vector<uint8_t> out(n, 0);
  if (n == 0 || !(voxel > 0)) return out;
  const VoxelGrid grid(xyz, voxel);
  // Breadth first from the voxels next to an empty one (L1), inwards.
  std::vector<uint8_t> layer(grid.size(), 0);
  std::deque<size_t> queue;
  for (size_t v = 0; v < grid.size(); ++v) {
    bool l1 = false;
    for_each_neighbour(grid, v, [&](int64_t w) { return !(l1 = w < 0); });
    if (l1) {
      layer[v] = 1;
      queue.push_back(v);
    }
  }
  while (!queue.empty()) {
    const size_t v = queue.front();
    queue.pop_front();
    for_each_neighbour(grid, v, [&](int64_t w) {
      if (w >= 0 && layer[size_t(w)] == 0) {
        layer[size_t(w)] = uint8_t(std::min(255, layer[v] + 1));
        queue.push_back(size_t(w));
      }
      return true;
    });
  }
  for (size_t v = 0; v < grid.size(); ++v) {
    const auto& vox = grid.voxel(v);
    for (uint32_t k = vox.first; k < vox.first + vox.count; ++k) out[grid.particle(k)] = layer[v];
  }
  return out;
}

}  // namespace sluice::io
