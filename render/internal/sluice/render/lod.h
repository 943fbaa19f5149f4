// sluice/render/lod.h: the continuous LOD rule, in host code. The compute
// shader (shaders/cull_particles.comp) implements the same arithmetic; tests
// compare the two and docs/render.md derives it.
//
// Thesis formula 3.1 gives a particle the value
//     lod = 1000 * max(1 - 0.7 * dc/dmax, 0.3) / (d * CLOD) * random
// (dc: distance of its projection from the screen centre, dmax: centre to
// corner, d: distance to the eye, CLOD: a data-range constant). Here
//     w   = max(1 - 0.7 * dc/dmax, 0.3) * d_ref / d        (importance; CLOD = 1000/d_ref)
//     lod = w * E,   E = -ln(1 - u)                        (random term, an Exp(1) variate)
// where u in [0,1) is the particle's stable 16-bit LOD value / 65536 (or the
// thesis's formula 3.2 hash of the position), and the particle is kept when
//     lod >= -ln(level)        <=>   keep probability p = level^(1/w).
// So level 1 keeps everything, level 0 nothing, a particle of importance 1
// survives with probability `level`, nearer or more central ones more often.
#pragma once

#include <cstdint>

namespace sluice::render {

// Importance w of a particle: `ndc_radius` = |ndc.xy| / sqrt(2) (0 centre, 1
// corner), `distance` to the eye, `reference_distance` = d_ref.
float lod_importance(float ndc_radius, float distance, float reference_distance);

// Probability that a particle of importance w survives threshold `level`.
float lod_keep_probability(float level, float importance);

// The uniform random term u in [0,1) from a stable 16-bit LOD value.
inline float lod_uniform(uint16_t value) { return (float(value) + 0.5f) * (1.0f / 65536.0f); }

// Thesis formula 3.2: fract(sin(dot(p, (12.9898, 78.233, 54.143))) * 437586.5453).
float lod_position_hash(float x, float y, float z);

// The exact keep decision the shader makes for random term u.
bool lod_keep(float level, float importance, float u);

// Splat growth in DensityPreserving mode: (1/p)^(1/3), at most max_scale.
float lod_splat_scale(float keep_probability, float max_scale);

}  // namespace sluice::render
