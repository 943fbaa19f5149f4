#include "sluice/io/types.h"

#include <algorithm>

namespace sluice::io {

void Aabb::extend(float x, float y, float z) {
  min[0] = std::min(min[0], x);
  min[1] = std::min(min[1], y);
  min[2] = std::min(min[2], z);
  max[0] = std::max(max[0], x);
  max[1] = std::max(max[1], y);
  max[2] = std::max(max[2], z);
}

void Aabb::extend(const Aabb& other) {
  if (other.empty()) return;
  extend(other.min[0], other.min[1], other.min[2]);
  extend(other.max[0], other.max[1], other.max[2]);
}

bool Aabb::contains(float x, float y, float z) const {
  return x >= min[0] && x <= max[0] && y >= min[1] && y <= max[1] && z >= min[2] && z <= max[2];
}

}  // namespace sluice::io
