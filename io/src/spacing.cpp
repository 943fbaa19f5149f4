#include "sluice/io/spacing.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::io {

float estimate_spacing(std::span<const float> xyz, size_t sample) {
  const size_t n = xyz.size() / 3;
  if (n < 2) return 0.f;
  Aabb box;
  for (size_t i = 0; i < n; ++i) box.extend(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  // Cells that would hold about two particles if they filled the box; a
  // neighbour within one cell is then found in the 27 cells around.
  double volume = 1;
  int flat_axes = 0;
  for (int a = 0; a < 3; ++a) {
    const double e = double(box.max[a]) - box.min[a];
    if (e > 0) volume *= e; else ++flat_axes;
  }
  const int dims = 3 - flat_axes;
  if (dims == 0) return 0.f;
  const double cell = std::pow(volume * 2.0 / double(n), 1.0 / dims);
  auto key = [&](size_t i) {
    uint64_t k = 0;
    for (int a = 0; a < 3; ++a) k = k * 2097152 + uint64_t((xyz[3 * i + a] - box.min[a]) / cell);
    return k;
  };
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  grid.reserve(n);
  for (size_t i = 0; i < n; ++i) grid[key(i)].push_back(uint32_t(i));

  std::vector<float> nearest;
  const size_t step = std::max<size_t>(1, n / sample);
  for (size_t i = 0; i < n; i += step) {
    double best = INFINITY;
    const int64_t c[3] = {int64_t((xyz[3 * i] - box.min[0]) / cell), int64_t((xyz[3 * i + 1] - box.min[1]) / cell),
                          int64_t((xyz[3 * i + 2] - box.min[2]) / cell)};
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (c[0] + dx < 0 || c[1] + dy < 0 || c[2] + dz < 0) continue;
          const uint64_t k = (uint64_t(c[0] + dx) * 2097152 + uint64_t(c[1] + dy)) * 2097152 + uint64_t(c[2] + dz);
          const auto it = grid.find(k);
          if (it == grid.end()) continue;
          for (uint32_t j : it->second) {
            if (j == i) continue;
            double d2 = 0;
            for (int a = 0; a < 3; ++a) d2 += std::pow(double(xyz[3 * i + a]) - xyz[3 * size_t(j) + a], 2);
            if (d2 > 0) best = std::min(best, d2);
          }
        }
    if (std::isfinite(best)) nearest.push_back(float(std::sqrt(best)));
  }
  if (nearest.empty()) return float(cell);
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return nearest[nearest.size() / 2];
}

}  // namespace sluice::io
