// sluice/render/band_classifier.h: the narrow band (io/narrow_band.h)
// classified on the GPU, for frames that arrive without layers.
//
// The same membership as io::classify_narrow_band, particle by particle:
// the same voxel grid (computed with the same float operations), L1, the
// selected L2 voxels with F2 = every particle, and isolated particles. The
// voxels live in a hash table keyed by their linear cell, so the grid must
// have fewer than 2^32 cells (a box of about 1600 voxels per side); beyond
// that classify() throws and the frame stays unlayered.
//
// Threads: one call at a time; it submits to the context's graphics queue
// and waits, so it must not overlap another thread's use of that queue
// (a Renderer on the same Context, for one).
#pragma once

#include <array>
#include <memory>
#include <span>
#include <vector>

#include "sluice/io/narrow_band.h"
#include "sluice/render/context.h"

namespace sluice::render {

class BandClassifier {
 public:
  // `context` must outlive the classifier.
  explicit BandClassifier(Context& context);
  ~BandClassifier();
  BandClassifier(const BandClassifier&) = delete;
  BandClassifier& operator=(const BandClassifier&) = delete;

  // Uploads `xyz` (x, y, z per particle, world units), classifies on the
  // GPU and reads the result back. options.f2 must be F2Test::All. The
  // result is io::classify_narrow_band's: layers, counts, voxel counts and,
  // with options.blobs, one blob per voxel holding interior particles (in
  // an order of the GPU's choosing; centroids summed in float). Throws
  // render::Error for bad options or more than 2^28 particles,
  // render::Error when the grid does not fit 32-bit keys or memory
  // runs out.
  io::NarrowBand classify(std::span<const float> xyz, const io::NarrowBandOptions& options);

  // Each particle's ellipsoid, as anisotropic particles draw it (Yu & Turk
  // 2013, shaders/band_ellipsoids.comp), from the particles within
  // 2 x `diameter` of it, weighted 1 - (r / 2 diameter)^3:
  // - shift: c minus the particle's position (world units), the centre
  //   it is drawn at: 0.5 times their weighted mean offset from it (the
  //   paper's smoothing of the centres, lambda);
  // - shape: the matrix A = R S^2 R^T (R: the ellipsoid's axes; S: its
  //   radii in units of the particle's radius), so that the particle of
  //   radius r at centre c covers (x - c)^T A^-1 (x - c) <= r^2; entries
  //   xx, xy, xz, yy, yz, zz. From the covariance of their centres
  //   smoothed with lambda 0.9 (the paper's), about its own. The radii keep
  //   the sphere's volume and differ at most 4 times.
  // A particle with fewer than 6 others near it is its sphere (A = I, no
  // shift). Half precision, as the GPU keeps them: about 1e-3 relative
  // (the shift: of the diameter). Throws as classify() does.
  struct Ellipsoid {
    std::array<float, 6> shape;
    std::array<float, 3> shift;
  };
  std::vector<Ellipsoid> ellipsoids(std::span<const float> xyz, float diameter);

  // GPU time of the last classify() (its passes, from timestamps; not the
  // upload or the read-back), milliseconds; < 0 when the device has no
  // timestamps.
  double last_gpu_ms() const;

  // The same, pass by pass (setup fills first, then band_bounds ...
  // band_blobs), for benchmarks that look for the slow one; empty without
  // timestamps.
  struct PassTime {
    const char* name;
    double ms;
  };
  std::vector<PassTime> last_pass_ms() const;

  // Whether the last classify() placed voxels by hashing their keys: its
  // grid had more cells than the table has slots (2n rounded up to a power
  // of two). Otherwise a voxel's slot is its cell.
  bool last_hashed() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sluice::render
