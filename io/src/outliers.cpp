#include "sluice/io/point_set.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace sluice::io {
namespace {

constexpr size_t kLeastParticles = 64;
constexpr size_t kMostSampled = 65536;

Aabb core_box(std::span<const float> xyz) {
  const size_t n = xyz.size() / 3;
  const size_t stride = std::max<size_t>(1, n / kMostSampled);
  std::vector<float> axis;
  axis.reserve(n / stride + 1);
  Aabb core;
  for (size_t a = 0; a < 3; ++a) {
    axis.clear();
    for (size_t i = 0; i < n; i += stride) axis.push_back(xyz[3 * i + a]);
    const size_t lo = axis.size() / 100, hi = axis.size() - 1 - axis.size() / 100;
    std::nth_element(axis.begin(), axis.begin() + ptrdiff_t(lo), axis.end());
    core.min[a] = axis[lo];
    std::nth_element(axis.begin(), axis.begin() + ptrdiff_t(hi), axis.end());
    core.max[a] = axis[hi];
  }
  return core;
}

float outside(const Aabb& core, const float* p) {
  float d = 0;
  for (size_t a = 0; a < 3; ++a) d = std::max({d, core.min[a] - p[a], p[a] - core.max[a]});
  return d;
}

struct Tally {
  Aabb bulk;
  uint64_t far = 0;
};

}  // namespace

FarReport report_far(const FarParticles& far, std::span<const float> xyz, bool dropped) {
  FarReport r;
  r.count = far.far.size();
  r.dropped = dropped;
  r.threshold = far.threshold;
  if (far.far.empty()) return r;
  r.farthest = far.farthest;
  for (size_t a = 0; a < 3; ++a) r.position[a] = xyz[3 * size_t(far.farthest) + a];
  return r;
}

FarParticles find_far_particles(std::span<const float> xyz, float spacing, float distance) {
  const size_t n = xyz.size() / 3;
  FarParticles out;
  if (n < kLeastParticles) {
    for (size_t i = 0; i < n; ++i) out.bulk.extend(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    out.threshold = INFINITY;
    return out;
  }
  const Aabb core = core_box(xyz);
  float diagonal = 0;
  for (size_t a = 0; a < 3; ++a) diagonal += (core.max[a] - core.min[a]) * (core.max[a] - core.min[a]);
  diagonal = std::sqrt(diagonal);
  out.threshold = distance > 0 ? distance : std::max(kFarSpacings * std::max(spacing, 0.0f), diagonal);
  // A frame gathered at one point (no spacing, no extent) has nothing to compare with.
  if (!(out.threshold > 0)) out.threshold = INFINITY;
  const float threshold = out.threshold;
  const Tally all = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 1 << 15), Tally{},
      [&](const tbb::blocked_range<size_t>& r, Tally t) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const float* p = &xyz[3 * i];
          if (outside(core, p) > threshold) ++t.far;
          else t.bulk.extend(p[0], p[1], p[2]);
        }
        return t;
      },
      [](Tally a, const Tally& b) {
        a.bulk.extend(b.bulk);
        a.far += b.far;
        return a;
      });
  out.bulk = all.bulk;
  if (all.far == 0) return out;
  out.far.reserve(all.far);
  for (size_t i = 0; i < n; ++i) {
    const float d = outside(core, &xyz[3 * i]);
    if (!(d > threshold)) continue;
    if (out.far.empty() || d > out.farthest_distance) {
      out.farthest = uint32_t(i);
      out.farthest_distance = d;
    }
    out.far.push_back(uint32_t(i));
  }
  return out;
}

}  // namespace sluice::io
