// sluice/io/point_set.h: what the converter works out from a frame's
// points: the particles far outside the rest of the frame, and the
// particles' spacing.
//
// Outliers: SPH runs fling the odd particle away (an escaped particle, a corrupt
// value): left in, one such particle widens the frame's box by orders of
// magnitude. The writer keeps far particles in chunks of their own (so
// every other chunk stays compact and quantizes within the file's bound)
// and leaves them out of the frame's display bounds; `convert` warns about
// them and `--drop-outliers` removes them.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::io {

// A particle is far when it lies more than this many particle spacings
// outside the frame's core box, and also more than the core's own diagonal.
inline constexpr float kFarSpacings = 100.0f;

struct FarParticles {
  Aabb bulk;                  // box of the particles that are not far (empty: none)
  std::vector<uint32_t> far;  // indices of the far particles, ascending
  float threshold = 0;        // world units outside the core beyond which a particle is far
  // The far particle farthest outside the core (when `far` is not empty).
  uint32_t farthest = 0;
  float farthest_distance = 0;
};

// What a frame's far particles were, for a warning: kept in chunks of their
// own (encode_frame), or left out (ConvertSettings::drop_far).
struct FarReport {
  uint64_t count = 0;
  bool dropped = false;
  float threshold = 0;              // world units outside the frame's core
  uint64_t farthest = 0;            // the farthest one's index in the frame
  std::array<float, 3> position{};  // and where it lies
};
// `far` found in `xyz` (the positions it was found in).
FarReport report_far(const FarParticles& far, std::span<const float> xyz, bool dropped);

// The core box spans the 1st to the 99th percentile of each axis, taken from
// at most 65,536 particles evenly spread over the frame. A particle is far
// when it lies more than `threshold` outside the core on some axis:
// `distance` when it is > 0 (world units), otherwise the larger of
// kFarSpacings x `spacing` and the core's diagonal. Frames of fewer than 64
// particles have no far particles (their percentiles say nothing). `xyz`
// holds finite x,y,z triples. Parallel (TBB); O(n).
FarParticles find_far_particles(std::span<const float> xyz, float spacing, float distance = 0);

// Spacing: estimating the particle spacing of a point set.

// Median distance from a particle to its nearest neighbour, over a sample of
// up to `sample` particles (a uniform grid over the bulk of the particles
// finds the neighbours; a few far-flung ones change neither the result nor
// the time, which is bounded by sample x 27 x 64 distance tests). Returns 0
// for fewer than two particles. Units: those of `xyz`.
float estimate_spacing(std::span<const float> xyz, size_t sample = 4096);

}  // namespace sluice::io
