// Particles from code rather than files (see synthetic.h).
#include "sluice/render/synthetic.h"
#include "sluice/error.h"
#include "sluice/io/lod.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace sluice::render {
namespace {

constexpr float kTank[3] = {2.0f, 1.0f, 1.0f};
constexpr uint32_t kBlock = 32;  // grid points per chunk edge

uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Height of the liquid over (x, y): a pool with waves and a column at x = 0
// that is collapsing towards +x.
float surface(float x, float y) {
  const float u = 1.0f - std::clamp((x - 0.35f) / 0.45f, 0.0f, 1.0f);
  const float column = 0.55f * u * u * (3.0f - 2.0f * u);
  return 0.28f + 0.035f * std::sin(7.0f * x + 1.3f) * std::cos(5.0f * y) + 0.02f * std::sin(13.0f * x + 9.0f * y) + column;
}

// Grid points (k = 0, 1, ...) of a column under height h: (k + 0.5) s < h.
uint32_t column_points(float h, float s) {
  const float a = h / s - 0.5f;
  return a > 0 ? uint32_t(std::ceil(a)) : 0u;
}

uint16_t quantize(float v, float lo, float hi) {
  if (hi <= lo) return 0;
  const float q = (v - lo) / (hi - lo) * 65535.0f + 0.5f;
  return uint16_t(std::clamp(q, 0.0f, 65535.0f));
}

struct Grid {
  float s;
  uint32_t n[3];   // grid points per axis
  uint32_t nb[3];  // blocks per axis
};

Grid make_grid(float s) {
  Grid g{};
  g.s = s;
  for (int a = 0; a < 3; ++a) {
    g.n[a] = std::max(1u, uint32_t(kTank[a] / s));
    g.nb[a] = (g.n[a] + kBlock - 1) / kBlock;
  }
  return g;
}

// The LOD value of grid point `id` and the jitter bits beside it.
uint64_t point_hash(uint64_t id) { return splitmix(id); }
uint16_t lod_value_of(uint64_t hash) { return uint16_t(hash >> 48); }

// Particles in block b (x-fastest block index) per LOD tier (io/lod.h):
// a block is written as a file writes a chunk, one record per tier.
// Untiered (`tiered` false): every particle in tier 0, in Morton order.
std::array<uint32_t, io::kLodTiers> block_tiers(const Grid& g, uint32_t bx, uint32_t by, uint32_t bz, bool tiered) {
  std::array<uint32_t, io::kLodTiers> tiers{};
  const uint32_t k0 = bz * kBlock;
  for (uint32_t j = by * kBlock; j < std::min(g.n[1], (by + 1) * kBlock); ++j) {
    for (uint32_t i = bx * kBlock; i < std::min(g.n[0], (bx + 1) * kBlock); ++i) {
      const uint32_t top = std::min(column_points(surface((float(i) + 0.5f) * g.s, (float(j) + 0.5f) * g.s), g.s), g.n[2]);
      for (uint32_t k = k0; k < std::min(top, k0 + kBlock); ++k) {
        const uint64_t id = (uint64_t(k) * g.n[1] + j) * g.n[0] + i;
        ++tiers[tiered ? io::lod_tier(lod_value_of(point_hash(id))) : 0];
      }
    }
  }
  return tiers;
}

// The non-empty 32^3 blocks of the grid, with their first particle, their
// particles per LOD tier and their first chunk row (one per non-empty tier).
struct Block {
  uint32_t b[3];
  uint32_t count;
  uint64_t first;
  std::array<uint32_t, io::kLodTiers> tiers;
  uint32_t first_row;
};
std::vector<Block> blocks_of(const Grid& g, bool tiered) {
  const uint64_t total_blocks = uint64_t(g.nb[0]) * g.nb[1] * g.nb[2];
  std::vector<std::array<uint32_t, io::kLodTiers>> tiers(total_blocks);
  const auto coords = [&](uint64_t b) {
    return std::array<uint32_t, 3>{uint32_t(b % g.nb[0]), uint32_t(b / g.nb[0] % g.nb[1]),
                                   uint32_t(b / (uint64_t(g.nb[0]) * g.nb[1]))};
  };
  tbb::parallel_for(uint64_t(0), total_blocks, [&](uint64_t b) {
    const auto c = coords(b);
    tiers[b] = block_tiers(g, c[0], c[1], c[2], tiered);
  });
  std::vector<Block> blocks;
  uint64_t first = 0;
  uint32_t rows = 0;
  for (uint64_t b = 0; b < total_blocks; ++b) {
    uint32_t count = 0, filled = 0;
    for (uint32_t n : tiers[b]) count += n, filled += n > 0;
    if (count == 0) continue;
    const auto c = coords(b);
    blocks.push_back({{c[0], c[1], c[2]}, count, first, tiers[b], rows});
    first += count;
    rows += filled;
  }
  return blocks;
}

uint32_t rows_of(const std::vector<Block>& blocks) {
  if (blocks.empty()) return 0;
  uint32_t filled = 0;
  for (uint32_t n : blocks.back().tiers) filled += n > 0;
  return blocks.back().first_row + filled;
}

// One block's particles: positions (jittered grid), attribute, LOD values,
// in the order a file stores them: tier by tier (io/lod.h), Morton order
// within a tier.
void generate_block(const Grid& g, const Block& b, bool tiered, std::vector<float>& pos, std::vector<float>& value,
                    std::vector<uint16_t>& lods) {
  const float s = g.s;
  pos.assign(3 * size_t(b.count), 0.0f);
  value.assign(b.count, 0.0f);
  lods.assign(b.count, 0);
  std::array<uint32_t, io::kLodTiers> at{};
  for (uint32_t t = 1; t < io::kLodTiers; ++t) at[t] = at[t - 1] + b.tiers[t - 1];
  // Each column's surface height and top grid point, then the block's
  // points in Morton order (as the encoder orders a chunk's particles).
  std::array<float, kBlock * kBlock> height{};
  std::array<uint32_t, kBlock * kBlock> top{};
  for (uint32_t y = 0; y < kBlock; ++y) {
    for (uint32_t x = 0; x < kBlock; ++x) {
      const uint32_t i = b.b[0] * kBlock + x, j = b.b[1] * kBlock + y;
      if (i >= g.n[0] || j >= g.n[1]) continue;
      height[y * kBlock + x] = surface((float(i) + 0.5f) * s, (float(j) + 0.5f) * s);
      top[y * kBlock + x] = std::min(column_points(height[y * kBlock + x], s), g.n[2]);
    }
  }
  const auto axis = [](uint32_t m) {  // every third bit of a Morton code
    uint32_t v = 0;
    for (uint32_t bit = 0; bit < 5; ++bit) v |= ((m >> (3 * bit)) & 1u) << bit;
    return v;
  };
  for (uint32_t m = 0; m < kBlock * kBlock * kBlock; ++m) {
    const uint32_t x = axis(m), y = axis(m >> 1), z = axis(m >> 2);
    const uint32_t i = b.b[0] * kBlock + x, j = b.b[1] * kBlock + y, k = b.b[2] * kBlock + z;
    if (i >= g.n[0] || j >= g.n[1] || k >= top[y * kBlock + x]) continue;
    const float h = height[y * kBlock + x];
    const uint64_t id = (uint64_t(k) * g.n[1] + j) * g.n[0] + i;
    const uint64_t r = point_hash(id);
    const auto jitter = [&](int shift) { return (float((r >> shift) & 0xffff) / 65535.0f - 0.5f) * 0.5f * s; };
    const float zw = (float(k) + 0.5f) * s + jitter(16);
    const uint32_t p = at[tiered ? io::lod_tier(lod_value_of(r)) : 0]++;
    pos[3 * size_t(p)] = (float(i) + 0.5f) * s + jitter(0);
    pos[3 * size_t(p) + 1] = (float(j) + 0.5f) * s + jitter(32);
    pos[3 * size_t(p) + 2] = zw;
    value[p] = std::clamp((h - zw) / 0.8f, 0.0f, 1.0f);
    lods[p] = lod_value_of(r);
  }
}

}  // namespace

SceneInfo scene_for_points(std::span<const float> xyz, float spacing, float attr_min, float attr_max) {
  SceneInfo s;
  s.bounds = {{1e30f, 1e30f, 1e30f}, {-1e30f, -1e30f, -1e30f}};
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) {
    for (int a = 0; a < 3; ++a) {
      s.bounds.min[a] = std::min(s.bounds.min[a], xyz[i + size_t(a)]);
      s.bounds.max[a] = std::max(s.bounds.max[a], xyz[i + size_t(a)]);
    }
  }
  if (xyz.empty()) s.bounds = {{0, 0, 0}, {1, 1, 1}};
  s.particle_spacing = spacing;
  s.particle_radius = spacing * 0.5f;
  s.coding = io::PositionCoding::Quantized16;
  s.attribute_names = {"value"};
  s.attribute_ranges = {{attr_min, attr_max}};
  s.max_particles = xyz.size() / 3;
  return s;
}

void upload_points(Renderer& renderer, std::span<const float> xyz, std::span<const uint16_t> lod,
                   std::span<const float> attribute, uint32_t chunk_particles) {
  const uint64_t n = xyz.size() / 3;
  if (lod.size() != n || (!attribute.empty() && attribute.size() != n) || chunk_particles == 0) {
    throw Error("upload_points: array sizes disagree");
  }
  const uint32_t chunks = uint32_t((n + chunk_particles - 1) / chunk_particles);
  FrameStaging st = renderer.stage_frame(n, chunks);
  if (st.stride != 8) throw Error("upload_points: the scene must use 16-bit quantized positions");
  tbb::parallel_for(uint32_t(0), chunks, [&](uint32_t c) {
    const uint64_t first = uint64_t(c) * chunk_particles;
    const uint64_t last = std::min(n, first + chunk_particles);
    GpuChunk& g = st.chunks[c];
    g = GpuChunk{};
    for (int a = 0; a < 3; ++a) {
      g.lo[a] = 1e30f;
      g.hi[a] = -1e30f;
    }
    g.attr_lo = 1e30f;
    g.attr_hi = -1e30f;
    for (uint64_t i = first; i < last; ++i) {
      for (int a = 0; a < 3; ++a) {
        g.lo[a] = std::min(g.lo[a], xyz[3 * i + size_t(a)]);
        g.hi[a] = std::max(g.hi[a], xyz[3 * i + size_t(a)]);
      }
      if (!attribute.empty()) {
        g.attr_lo = std::min(g.attr_lo, attribute[i]);
        g.attr_hi = std::max(g.attr_hi, attribute[i]);
      }
    }
    if (attribute.empty()) g.attr_lo = g.attr_hi = 0;
    g.first = uint32_t(first);
    g.count = uint32_t(last - first);
    auto* out = reinterpret_cast<uint16_t*>(st.particles.data());
    for (uint64_t i = first; i < last; ++i) {
      for (int a = 0; a < 3; ++a) out[4 * i + size_t(a)] = quantize(xyz[3 * i + size_t(a)], g.lo[a], g.hi[a]);
      out[4 * i + 3] = lod[i];
      if (!st.color_attribute.empty()) {
        st.color_attribute[i] = attribute.empty() ? 0 : quantize(attribute[i], g.attr_lo, g.attr_hi);
      }
    }
  });
  renderer.wait_upload(renderer.commit_frame());
}

SyntheticFluid synthetic_fluid(uint64_t target, bool tiers) {
  if (target == 0) throw Error("synthetic_fluid: zero particles");
  // Liquid volume by midpoint sampling, then the spacing that gives `target`.
  double volume = 0;
  const int samples = 400;
  for (int j = 0; j < samples; ++j) {
    for (int i = 0; i < 2 * samples; ++i) {
      volume += surface((float(i) + 0.5f) / float(samples), (float(j) + 0.5f) / float(samples));
    }
  }
  volume /= double(samples) * double(samples);
  float s = float(std::cbrt(volume / double(target)));
  SyntheticFluid f;
  f.tiers = tiers;
  // Refine once on the exact count (the grid discretizes the surface).
  for (int pass = 0; pass < 2; ++pass) {
    const Grid g = make_grid(s);
    uint64_t count = 0;
    for (uint32_t j = 0; j < g.n[1]; ++j) {
      for (uint32_t i = 0; i < g.n[0]; ++i) {
        count += std::min(column_points(surface((float(i) + 0.5f) * s, (float(j) + 0.5f) * s), s), g.n[2]);
      }
    }
    f.particles = count;
    if (pass == 0) s *= float(std::cbrt(double(count) / double(target)));
  }
  if (f.particles > UINT32_MAX) throw Error("synthetic_fluid: more than 2^32 particles");
  const Grid g = make_grid(s);
  f.spacing = s;
  const uint64_t chunks = rows_of(blocks_of(g, tiers));
  f.chunks = uint32_t(chunks);
  f.scene.bounds = {{0, 0, 0}, {kTank[0], kTank[1], kTank[2]}};
  f.scene.particle_spacing = s;
  f.scene.particle_radius = 0.5f * s;
  f.scene.coding = io::PositionCoding::Quantized16;
  f.scene.attribute_names = {"depth"};
  f.scene.attribute_ranges = {{0.0f, 1.0f}};
  f.scene.max_particles = f.particles;
  f.scene.max_chunks = chunks;
  return f;
}

std::vector<float> synthetic_points(const SyntheticFluid& f) {
  const Grid g = make_grid(f.spacing);
  const std::vector<Block> blocks = blocks_of(g, f.tiers);
  std::vector<float> out(3 * f.particles);
  tbb::parallel_for(size_t(0), blocks.size(), [&](size_t bi) {
    std::vector<float> pos, value;
    std::vector<uint16_t> lods;
    generate_block(g, blocks[bi], f.tiers, pos, value, lods);
    std::copy(pos.begin(), pos.end(), out.begin() + std::ptrdiff_t(3 * blocks[bi].first));
  });
  return out;
}

void upload_synthetic(Renderer& renderer, const SyntheticFluid& f) {
  const Grid g = make_grid(f.spacing);
  const std::vector<Block> blocks = blocks_of(g, f.tiers);
  const uint64_t total = blocks.empty() ? 0 : blocks.back().first + blocks.back().count;
  if (total != f.particles) throw Error("upload_synthetic: particle count changed");
  FrameStaging st = renderer.stage_frame(total, rows_of(blocks));
  auto* out = reinterpret_cast<uint16_t*>(st.particles.data());
  tbb::parallel_for(size_t(0), blocks.size(), [&](size_t bi) {
    const Block& b = blocks[bi];
    thread_local std::vector<float> pos, value;
    thread_local std::vector<uint16_t> lods;
    generate_block(g, b, f.tiers, pos, value, lods);
    // The block's box and attribute range, shared by its tiers' rows (as a
    // file's cell is): a particle decodes the same whichever tiers are drawn.
    GpuChunk block{};
    for (int a = 0; a < 3; ++a) {
      block.lo[a] = 1e30f;
      block.hi[a] = -1e30f;
    }
    for (size_t p = 0; p < lods.size(); ++p) {
      for (int a = 0; a < 3; ++a) {
        block.lo[a] = std::min(block.lo[a], pos[3 * p + size_t(a)]);
        block.hi[a] = std::max(block.hi[a], pos[3 * p + size_t(a)]);
      }
    }
    block.attr_lo = *std::min_element(value.begin(), value.end());
    block.attr_hi = *std::max_element(value.begin(), value.end());
    uint32_t row = b.first_row, first = 0;
    for (uint32_t t = 0; t < io::kLodTiers; ++t) {
      if (b.tiers[t] == 0) continue;
      GpuChunk& c = st.chunks[row++];
      c = block;
      c.first = uint32_t(b.first + first);
      c.count = b.tiers[t];
      const auto [lo, hi] = std::minmax_element(lods.begin() + first, lods.begin() + first + b.tiers[t]);
      c.lod_lo = *lo;
      c.lod_hi = *hi;
      first += b.tiers[t];
    }
    for (size_t p = 0; p < lods.size(); ++p) {
      const uint64_t i = b.first + p;
      for (int a = 0; a < 3; ++a) out[4 * i + size_t(a)] = quantize(pos[3 * p + size_t(a)], block.lo[a], block.hi[a]);
      out[4 * i + 3] = lods[p];
      if (!st.color_attribute.empty()) st.color_attribute[i] = quantize(value[p], block.attr_lo, block.attr_hi);
    }
  });
  renderer.wait_upload(renderer.commit_frame());
}

}  // namespace sluice::render
