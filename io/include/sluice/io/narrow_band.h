// sluice/io/narrow_band.h: which particles can be seen from outside the
// fluid (the narrow band), by the Layered Neighborhood Method (LNM) of
// Oliveira's dissertation (papers/001, section 3.2.1), and the exact
// reference it approximates.
//
// Voxels of side d cover the particles' bounding box. L0 voxels are empty;
// an occupied voxel with an L0 (or outside) voxel among its 26 neighbours
// is L1, and all its particles are surface. An occupied voxel next to an L1
// voxel that holds at most n1 = (d/h)^3 particles (too few to hide what lies
// behind it) is a selected L2 voxel; the particles in it pass the F2 test
// chosen. Everything else is interior. A particle with no neighbour within
// 2h (spray, a droplet) is surface whatever its voxel.
//
// Plain functions over caller-owned positions; TBB-parallel over voxels and
// particles. Units: those of the positions.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace sluice::io {

// Where a particle is, by the classification.
enum class BandLayer : uint8_t {
  Interior = 0,
  L1 = 1,        // in an L1 voxel: surface
  L2 = 2,        // in a selected L2 voxel and passing F2: surface
  Isolated = 3,  // no neighbour within 2h: surface
};

inline bool is_surface(BandLayer l) { return l != BandLayer::Interior; }

// The F2 test for particles of selected L2 voxels (section 3.2.1.2).
enum class F2Test : uint8_t {
  All,        // every particle (equation 3.15, the dissertation's choice)
  Asymmetry,  // |x_i - sum_j x_j W(x_j - x_i)| > 0.1 h over the 27 voxels around (its comparison)
};

struct NarrowBandOptions {
  float diameter = 0;  // h, the particle diameter (the rest spacing); must be > 0
  float voxel = 0;     // d; 0: 2h (d = 4r, as the dissertation's tests)
  F2Test f2 = F2Test::All;
  bool blobs = false;  // also gather the interior particles of each voxel into a blob
};

// The interior particles of one voxel, standing in for them where only the
// fluid's thickness is wanted (dissertation section 4, equation 4.3).
struct VoxelBlob {
  std::array<float, 3> centroid{};  // mean position of its particles
  uint32_t count = 0;               // particles it stands for (>= 1)
};

struct NarrowBand {
  std::vector<BandLayer> layer;        // per particle, in input order
  std::array<uint64_t, 4> counts{};    // particles per BandLayer
  uint64_t voxels = 0;                 // occupied voxels
  uint64_t l1_voxels = 0, l2_voxels = 0;  // L1, selected L2
  float voxel = 0;                     // d used
  // With options.blobs: one blob per voxel holding interior particles, and
  // for every particle the blob it belongs to (kNoBlob for surface ones).
  std::vector<VoxelBlob> blobs;
  std::vector<uint32_t> blob_of;
  static constexpr uint32_t kNoBlob = UINT32_MAX;
  uint64_t surface() const { return counts[1] + counts[2] + counts[3]; }
};

// Classifies `xyz` (x,y,z per particle). Throws io::Error when
// options.diameter is not positive.
NarrowBand classify_narrow_band(std::span<const float> xyz, const NarrowBandOptions& options);

// The exact narrow band, for tests and statistics: the particles on the
// boundary of the union of spheres of radius h around every particle (its
// reach: at the rest spacing neighbours' spheres overlap, so inside the
// fluid every point of such a sphere lies within h of another particle).
// A particle belongs to it when some point at distance h from it is farther
// than h from every other particle, sampled at `directions` points per
// particle (a Fibonacci sphere): exact up to that sampling, and slow.
std::vector<bool> exact_narrow_band(std::span<const float> xyz, float diameter, int directions = 64);

// The LNM layer index of every particle's voxel: 1 + the Chebyshev distance
// (in voxels) to the nearest empty voxel or the outside, as equation 3.11
// defines L_s. For the statistic of the dissertation's tables 1 and 2 (how
// much of the exact narrow band lies in L1, L2, L3, ...).
std::vector<uint8_t> voxel_layers(std::span<const float> xyz, float voxel);

}  // namespace sluice::io
