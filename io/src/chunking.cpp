#include "chunking.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
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
  Splitter(const std::vector<Keyed>& keys, uint32_t max_particles, ChunkPlan& plan)
      : keys_(keys), max_(max_particles), plan_(plan) {}

  // Cuts [begin, end), whose codes share their top `level` octree digits.
  void split(uint32_t begin, uint32_t end, int level) {
    if (end - begin <= max_) return emit(begin, end);
    if (level == kLevels) {  // identical codes: cut evenly
      for (uint32_t b = begin; b < end; b += max_) emit(b, std::min(end, b + max_));
      return;
    }
    const int shift = 3 * (kLevels - 1 - level);
    uint32_t group_begin = begin, group_end = begin;
    uint32_t child_begin = begin;
    while (child_begin < end) {
      const uint64_t child_hi = (keys_[child_begin].code | ((uint64_t{1} << shift) - 1));
      const auto it = std::upper_bound(keys_.begin() + child_begin, keys_.begin() + end, Keyed{child_hi, UINT32_MAX});
      const auto child_end = static_cast<uint32_t>(it - keys_.begin());
      const uint32_t count = child_end - child_begin;
      if (count > max_) {
        flush(group_begin, group_end);
        split(child_begin, child_end, level + 1);
        group_begin = group_end = child_end;
      } else if (group_end - group_begin + count > max_) {
        flush(group_begin, group_end);
        group_begin = child_begin;
        group_end = child_end;
      } else {
        group_end = child_end;
      }
      child_begin = child_end;
    }
    flush(group_begin, group_end);
  }

 private:
  void flush(uint32_t begin, uint32_t end) {
    if (end > begin) emit(begin, end);
  }
  void emit(uint32_t begin, uint32_t end) { plan_.chunks.push_back({begin, end}); }

  const std::vector<Keyed>& keys_;
  uint32_t max_;
  ChunkPlan& plan_;
};

}  // namespace

ChunkPlan plan_chunks(std::span<const float> xyz, const Aabb& bounds, uint32_t max_particles) {
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
  plan.order.resize(n);
  for (size_t i = 0; i < n; ++i) plan.order[i] = keys[i].index;
  Splitter(keys, std::max<uint32_t>(1, max_particles), plan).split(0, static_cast<uint32_t>(n), 0);
  return plan;
}

}  // namespace sluice::io
