// sluice/io/spacing.h: estimating the particle spacing of a point set.
#pragma once

#include <span>

namespace sluice::io {

// Median distance from a particle to its nearest neighbour, over a sample of
// up to `sample` particles (a uniform grid over the bulk of the particles
// finds the neighbours; a few far-flung ones change neither the result nor
// the time, which is bounded by sample x 27 x 64 distance tests). Returns 0
// for fewer than two particles. Units: those of `xyz`.
float estimate_spacing(std::span<const float> xyz, size_t sample = 4096);

}  // namespace sluice::io
