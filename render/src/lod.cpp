// Host reference of the cLOD rule (see lod.h and shaders/cull_particles.comp).
#include "sluice/render/lod.h"

#include <algorithm>
#include <cmath>

namespace sluice::render {

float lod_importance(float ndc_radius, float distance, float reference_distance) {
  const float centre = std::max(1.0f - 0.7f * std::min(ndc_radius, 1.0f), 0.3f);
  return centre * reference_distance / std::max(distance, 1e-20f);
}

float lod_keep_probability(float level, float importance) {
  if (level >= 1) return 1;
  if (level <= 0) return 0;
  return std::pow(level, 1.0f / importance);
}

float lod_position_hash(float x, float y, float z) {
  const float s = std::sin(x * 12.9898f + y * 78.233f + z * 54.143f) * 437586.5453f;
  return s - std::floor(s);
}

bool lod_keep(float level, float importance, float u) {
  const float threshold = level > 0 ? -std::log(std::min(level, 1.0f)) : 1e30f;
  return importance * -std::log(1.0f - u) >= threshold;
}

float lod_splat_scale(float keep_probability, float max_scale) {
  if (keep_probability <= 0) return max_scale;
  return std::min(std::cbrt(1.0f / keep_probability), max_scale);
}

}  // namespace sluice::render
