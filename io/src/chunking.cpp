#include "chunking.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "morton.h"

namespace sluice::io {
namespace {

constexpr int kLevels = 21;  // bits per axis of the ordering code

struct Keyed {
  uint64_t code;
  uint32_t index;
  bool operator<(const Keyed& o) const { return code < o.code || (code == o.code && index < o.index); }
};

class Splitter {
 public:
  Splitter(std::vector<Keyed>& keys, std::span<const float> xyz, const Aabb& bounds, uint32_t max_particles,
           float max_extent, ChunkPlan& plan)
      : keys_(keys), xyz_(xyz), max_(max_particles), max_extent_(max_extent), plan_(plan) {
    float widest = 0;
    for (int a = 0; a < 3; ++a) widest = std::max(widest, bounds.max[size_t(a)] - bounds.min[size_t(a)]);
    // A little wider than the cell: a particle on a face may round into the cell beside it.
    for (int level = 0; level <= kLevels; ++level) cell_extent_[size_t(level)] = std::ldexp(widest, -level) * 1.001f;
  }

  // Cuts [begin, end), whose codes share their top `level` octree digits.
  void split(uint32_t begin, uint32_t end, int level) {
    if (end - begin <= max_ && fits(begin, end, level)) return emit(begin, end);
    if (level == kLevels) return halve(begin, end);  // identical codes
    const int shift = 3 * (kLevels - 1 - level);
    // Siblings group while they fit; their box is tracked only where the
    // cell itself may be wider than the limit.
    const bool check = !(cell_extent_[size_t(level)] <= max_extent_);
    uint32_t group_begin = begin, group_end = begin;
    Aabb group_box;
    uint32_t child_begin = begin;
    while (child_begin < end) {
      const uint64_t child_hi = (keys_[child_begin].code | ((uint64_t{1} << shift) - 1));
      const auto it = std::upper_bound(keys_.begin() + child_begin, keys_.begin() + end, Keyed{child_hi, UINT32_MAX});
      const auto child_end = static_cast<uint32_t>(it - keys_.begin());
      const uint32_t count = child_end - child_begin;
      const Aabb child_box = check ? box(child_begin, child_end) : Aabb{};
      if (count > max_ || (check && !narrow(child_box))) {
        flush(group_begin, group_end);
        split(child_begin, child_end, level + 1);
        group_begin = group_end = child_end;
        group_box = Aabb{};
      } else {
        Aabb joined = group_box;
        if (check) joined.extend(child_box);
        if (group_end - group_begin + count > max_ || (check && !narrow(joined))) {
          flush(group_begin, group_end);
          group_begin = child_begin;
          group_end = child_end;
          group_box = child_box;
        } else {
          group_end = child_end;
          group_box = joined;
        }
      }
      child_begin = child_end;
    }
    flush(group_begin, group_end);
  }

 private:
  bool fits(uint32_t begin, uint32_t end, int level) const {
    return cell_extent_[size_t(level)] <= max_extent_ || narrow(box(begin, end));
  }
  bool narrow(const Aabb& b) const {
    if (b.empty()) return true;
    for (int a = 0; a < 3; ++a) {
      if (!(b.max[size_t(a)] - b.min[size_t(a)] <= max_extent_)) return false;
    }
    return true;
  }
  Aabb box(uint32_t begin, uint32_t end) const {
    Aabb b;
    for (uint32_t k = begin; k < end; ++k) {
      const size_t i = 3 * size_t(keys_[k].index);
      b.extend(xyz_[i], xyz_[i + 1], xyz_[i + 2]);
    }
    return b;
  }
  // Particles with one code (their cell is still too wide, or too full):
  // too full only, cut into runs of max_; too wide, halved along the
  // widest axis, by count, until both limits hold. Codes stay sorted (they
  // are all equal).
  void halve(uint32_t begin, uint32_t end) {
    const Aabb b = box(begin, end);
    if (narrow(b)) {  // only too full: cut evenly, as few chunks as the count needs
      for (uint32_t at = begin; at < end; at += max_) emit(at, std::min(end, at + max_));
      return;
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (b.max[size_t(a)] - b.min[size_t(a)] > b.max[size_t(axis)] - b.min[size_t(axis)]) axis = a;
    }
    const uint32_t middle = begin + (end - begin) / 2;
    std::nth_element(keys_.begin() + begin, keys_.begin() + middle, keys_.begin() + end, [&](const Keyed& l, const Keyed& r) {
      const float x = xyz_[3 * size_t(l.index) + size_t(axis)], y = xyz_[3 * size_t(r.index) + size_t(axis)];
      return x < y || (x == y && l.index < r.index);
    });
    halve(begin, middle);
    halve(middle, end);
  }
  void flush(uint32_t begin, uint32_t end) {
    if (end > begin) emit(begin, end);
  }
  void emit(uint32_t begin, uint32_t end) { plan_.chunks.push_back({begin, end}); }

  std::vector<Keyed>& keys_;
  std::span<const float> xyz_;
  uint32_t max_;
  float max_extent_;
  std::array<float, kLevels + 1> cell_extent_{};
  ChunkPlan& plan_;
};

}  // namespace

ChunkPlan plan_chunks(std::span<const float> xyz, const Aabb& bounds, uint32_t max_particles, float max_extent) {
  const size_t n = xyz.size() / 3;
  ChunkPlan plan;
  if (n == 0) return plan;
  std::vector<Keyed> keys(n);
  const double top = double((1u << kLevels) - 1);
  std::array<double, 3> scale{};
  for (int a = 0; a < 3; ++a) {
    const double extent = double(bounds.max[a]) - double(bounds.min[a]);
    scale[a] = extent > 0 ? top / extent : 0.0;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 14), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      std::array<uint32_t, 3> q{};
      for (int a = 0; a < 3; ++a) {
        const double t = (double(xyz[3 * i + a]) - bounds.min[a]) * scale[a];
        q[a] = static_cast<uint32_t>(std::clamp(t, 0.0, top));
      }
      keys[i] = {morton_encode(q[0], q[1], q[2]), static_cast<uint32_t>(i)};
    }
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  Splitter(keys, xyz, bounds, std::max<uint32_t>(1, max_particles), max_extent, plan).split(0, static_cast<uint32_t>(n), 0);
  plan.order.resize(n);
  for (size_t i = 0; i < n; ++i) plan.order[i] = keys[i].index;
  return plan;
}

}  // namespace sluice::io
