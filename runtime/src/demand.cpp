// The view's demand: tiers per cell from the views' frusta and the cLOD
// bound (demand.h). Mirrors shaders/cull_chunks.comp and cull_particles.comp.
#include "sluice/runtime/demand.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sluice/io/lod.h"

namespace sluice::runtime {
namespace {

// Element (row r, column c) of a column-major matrix.
float at(const std::array<float, 16>& m, int r, int c) { return m[size_t(c) * 4 + size_t(r)]; }

// Row r of projection * view.
std::array<double, 4> vp_row(const DemandView& v, int r) {
  std::array<double, 4> out{};
  for (int c = 0; c < 4; ++c) {
    double sum = 0;
    for (int k = 0; k < 4; ++k) sum += double(at(v.projection, r, k)) * at(v.view, k, c);
    out[size_t(c)] = sum;
  }
  return out;
}

struct Box {
  float lo[3], hi[3];
};

Box grown(const io::Aabb& b, float by) {
  Box out{};
  for (int a = 0; a < 3; ++a) {
    out.lo[a] = b.min[size_t(a)] - by;
    out.hi[a] = b.max[size_t(a)] + by;
  }
  return out;
}

// A view's left, right, bottom, top and near planes (as globals.cpp makes
// them for the chunk pass), normalised: made once per demand, not per cell.
using Frustum = std::array<std::array<double, 4>, 5>;

Frustum frustum_of(const DemandView& v) {
  const std::array<double, 4> r0 = vp_row(v, 0), r1 = vp_row(v, 1), r2 = vp_row(v, 2), r3 = vp_row(v, 3);
  const bool reversed = at(v.projection, 2, 3) > 0;
  Frustum planes{};
  for (size_t i = 0; i < 4; ++i) {
    planes[0][i] = r3[i] + r0[i];
    planes[1][i] = r3[i] - r0[i];
    planes[2][i] = r3[i] + r1[i];
    planes[3][i] = r3[i] - r1[i];
    planes[4][i] = reversed ? r3[i] - r2[i] : r2[i];
  }
  for (auto& p : planes) {
    const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double& x : p) x = len > 0 ? x / len : 0;
  }
  return planes;
}

// The box lies on the inner side of every plane, as the chunk pass tests it
// (positive vertex), within a tolerance for the shader's float arithmetic.
bool visible(const Frustum& planes, const Box& b) {
  const double tolerance = 1e-5 * (1.0 + std::abs(b.hi[0]) + std::abs(b.hi[1]) + std::abs(b.hi[2]));
  for (const auto& p : planes) {
    double d = p[3];
    for (int a = 0; a < 3; ++a) d += p[size_t(a)] * (p[size_t(a)] >= 0 ? b.hi[a] : b.lo[a]);
    if (d < -tolerance) return false;
  }
  return true;
}

// What the rule needs of a demand beyond its fields: each view's frustum.
struct Prepared {
  io::InlineVector<Frustum, 4> frusta;
};

Prepared prepare(const ViewDemand& demand) {
  Prepared p;
  for (size_t i = 0; i < demand.views.size(); ++i) p.frusta.push_back(frustum_of(demand.views[i]));
  return p;
}

// The largest importance w any point of the box can have in this view:
// c / d * d_ref with c from the smallest |ndc| and d the smallest eye
// distance, each bounded over the eye-space box of the corners.
double largest_importance(const DemandView& v, const Box& b, double d_ref) {
  double elo[3] = {1e300, 1e300, 1e300}, ehi[3] = {-1e300, -1e300, -1e300};
  double nlo[2] = {1e300, 1e300}, nhi[2] = {-1e300, -1e300};
  bool behind = false;
  for (int corner = 0; corner < 8; ++corner) {
    const double p[3] = {(corner & 1) ? b.hi[0] : b.lo[0], (corner & 2) ? b.hi[1] : b.lo[1], (corner & 4) ? b.hi[2] : b.lo[2]};
    double e[3];
    for (int r = 0; r < 3; ++r) e[r] = at(v.view, r, 0) * p[0] + at(v.view, r, 1) * p[1] + at(v.view, r, 2) * p[2] + at(v.view, r, 3);
    for (int r = 0; r < 3; ++r) {
      elo[r] = std::min(elo[r], e[r]);
      ehi[r] = std::max(ehi[r], e[r]);
    }
    const double depth = -e[2];
    if (depth <= 1e-12) {
      behind = true;
      continue;
    }
    // As cull_particles.comp: ndc = (P00 x, P11 y) / depth - (P02, P12).
    const double nx = at(v.projection, 0, 0) * e[0] / depth - at(v.projection, 0, 2);
    const double ny = at(v.projection, 1, 1) * e[1] / depth - at(v.projection, 1, 2);
    nlo[0] = std::min(nlo[0], nx);
    nhi[0] = std::max(nhi[0], nx);
    nlo[1] = std::min(nlo[1], ny);
    nhi[1] = std::max(nhi[1], ny);
  }
  double d2 = 0;
  for (int r = 0; r < 3; ++r) {
    const double gap = elo[r] > 0 ? elo[r] : ehi[r] < 0 ? -ehi[r] : 0;
    d2 += gap * gap;
  }
  const double distance = std::sqrt(d2);
  if (distance <= 0) return std::numeric_limits<double>::infinity();
  double centre = 1;
  if (!behind) {
    const double gx = nlo[0] > 0 ? nlo[0] : nhi[0] < 0 ? -nhi[0] : 0;
    const double gy = nlo[1] > 0 ? nlo[1] : nhi[1] < 0 ? -nhi[1] : 0;
    const double radius = std::sqrt(gx * gx + gy * gy) * 0.70710678118654752;
    centre = std::max(1.0 - 0.7 * std::min(radius, 1.0), 0.3);
  }
  return centre * d_ref / distance;
}

// The reach of a blob's splat (render's common.glsl: kBlobReach sigmas).
float blob_reach(float voxel, float radius) {
  const float sigma = std::sqrt(std::max(voxel * voxel / 12.0f + radius * radius / 5.0f, 0.25f * voxel * voxel));
  return 2.5f * sigma;
}

uint32_t tiers_needed(const ViewDemand& demand, const Prepared& prepared, const io::Aabb& box, io::Layer layer,
                      float blob_voxel) {
  if (demand.everything()) return io::kLodTiers;
  if (demand.views.size() == 0) return demand.level > 0 ? std::max<uint32_t>(1, io::tiers_for_keep(demand.level)) : 1;
  const bool blob = layer == io::Layer::Blobs;
  const float reach = blob ? blob_reach(blob_voxel, demand.particle_radius) : demand.particle_reach;
  const Box seen = grown(box, reach + demand.margin);
  bool any = false;
  for (size_t i = 0; i < prepared.frusta.size() && !any; ++i) any = visible(prepared.frusta[i], seen);
  if (!any) return 0;
  if (!demand.lod) return io::kLodTiers;
  if (!(demand.level < 1)) return io::kLodTiers;
  if (!(demand.level > 0)) return 1;  // nothing is kept; the first tier keeps a visible cell from being empty
  const Box near = grown(box, demand.margin);
  const double d_ref = std::max<double>(demand.reference_distance, 1e-30);
  double w = 0;
  for (size_t i = 0; i < demand.views.size(); ++i) w = std::max(w, largest_importance(demand.views[i], near, d_ref));
  if (!std::isfinite(w)) return io::kLodTiers;
  w *= 1.0 + 1e-4;  // the shader's float arithmetic
  const double keep = std::pow(double(demand.level), 1.0 / std::max(w, 1e-30));
  return std::max<uint32_t>(1, io::tiers_for_keep(keep));
}

// The longest a world displacement of at most `shift[a]` along each axis
// can be in eye space: the view matrix's columns may scale (an XR world
// scale), so each axis counts with its column's length.
double eye_shift(const DemandView& v, const std::array<double, 3>& shift) {
  double out = 0;
  for (int a = 0; a < 3; ++a) {
    const double x = at(v.view, 0, a), y = at(v.view, 1, a), z = at(v.view, 2, a);
    out += shift[size_t(a)] * std::sqrt(x * x + y * y + z * z);
  }
  return out;
}

// How far, along each world axis, the coarse fill may put a particle of
// `box` from its full-precision position: io::kCoarseSteps quantization
// steps, plus the float rounding of two dequantizations.
std::array<double, 3> coarse_steps(const io::Aabb& box) {
  std::array<double, 3> shift{};
  for (int a = 0; a < 3; ++a) {
    const double lo = box.min[size_t(a)], hi = box.max[size_t(a)];
    const double ulp = 2.0 * std::numeric_limits<float>::epsilon() * std::max(std::abs(lo), std::abs(hi));
    shift[size_t(a)] = double(io::kCoarseSteps[size_t(a)]) * (hi - lo) / 65535.0 + 2 * ulp;
  }
  return shift;
}

// ... and in eye space.
double coarse_shift(const DemandView& v, const io::Aabb& box) { return eye_shift(v, coarse_steps(box)); }

// The largest distance, in pixels, the coarse precision can move a
// particle of box `box` on `view`'s screen (within half a screen of its
// viewport: farther ones are not drawn), for views up to `margin` away
// (infinity where it cannot be bounded): what coarse_enough() compares.
double coarse_error_pixels(const DemandView& v, const io::Aabb& box, float margin) {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  if (v.width == 0 || v.height == 0) return kInfinity;
  const double moved = coarse_shift(v, box);
  // ndc = clip.xy / clip.w. An eye-space shift d moves it by
  // (row_k . d) / w - ndc (row_3 . d) / w: at most
  // moved (|row_k| + |ndc| |row_3|) / w, for w at its smallest over the
  // box (grown by the margin) and particles within half a screen of the
  // viewport (|ndc| <= 1.5: farther ones are not drawn).
  const Box b = grown(box, margin);
  double w_least = kInfinity;
  for (int corner = 0; corner < 8; ++corner) {
    const double p[3] = {(corner & 1) ? b.hi[0] : b.lo[0], (corner & 2) ? b.hi[1] : b.lo[1], (corner & 4) ? b.hi[2] : b.lo[2]};
    double e[4] = {0, 0, 0, 1};
    for (int r = 0; r < 3; ++r) e[r] = at(v.view, r, 0) * p[0] + at(v.view, r, 1) * p[1] + at(v.view, r, 2) * p[2] + at(v.view, r, 3);
    double w = 0;
    for (int k = 0; k < 4; ++k) w += at(v.projection, 3, k) * e[k];
    w_least = std::min(w_least, w);
  }
  if (!(w_least > 1e-9)) return kInfinity;  // the eye may reach the box
  auto row_length = [&](int r) {
    return std::sqrt(double(at(v.projection, r, 0)) * at(v.projection, r, 0) + double(at(v.projection, r, 1)) * at(v.projection, r, 1) +
                     double(at(v.projection, r, 2)) * at(v.projection, r, 2));
  };
  constexpr double kNdcReach = 1.5;
  const double w_row = row_length(3);
  const double x = 0.5 * v.width * moved * (row_length(0) + kNdcReach * w_row) / w_least;
  const double y = 0.5 * v.height * moved * (row_length(1) + kNdcReach * w_row) / w_least;
  return std::hypot(x, y);
}

}  // namespace

bool coarse_enough(const ViewDemand& demand, const io::Aabb& box, io::Layer layer) {
  // A blob's random term hashes the voxel its decoded centroid lies in
  // (io::blob_lod_uniform), which the writer keeps 1e-3 of a side from any
  // face; the coarse fill moves a centroid up to 0.05 of a side (32 steps of
  // a box 100 sides wide): other blobs would be kept. Blobs are read whole.
  if (layer == io::Layer::Blobs) return false;
  if (!(demand.position_error_pixels > 0) || demand.views.size() == 0) return false;
  // Against the splat too (world units, whatever the view): a shift that is
  // a fraction of a pixel can still be a large share of a particle drawn
  // smaller than a pixel, and moves the fluid's depth (and so its normals)
  // by that share.
  const std::array<double, 3> steps = coarse_steps(box);
  if (!(steps[0] + steps[1] + steps[2] <= double(kCoarseSplatShare) * demand.particle_radius)) return false;
  for (size_t i = 0; i < demand.views.size(); ++i) {
    if (!(coarse_error_pixels(demand.views[i], box, demand.margin) <= demand.position_error_pixels)) return false;
  }
  return true;
}

uint32_t tiers_needed(const ViewDemand& demand, const io::Aabb& box, io::Layer layer, float blob_voxel) {
  return tiers_needed(demand, prepare(demand), box, layer, blob_voxel);
}

namespace {

// Marks the fine parts of `frame`'s records coarse_enough() leaves out.
void drop_fine_parts(const ViewDemand& demand, io::FrameHeader& frame) {
  if (!frame.split_positions) return;
  for (io::ChunkDesc& c : frame.chunks) c.fine.dropped = c.fine.split() && coarse_enough(demand, c.bounds, c.layer);
}

}  // namespace

void apply_demand(const ViewDemand& demand, io::FrameHeader& frame) {
  if (demand.everything()) return;
  const float voxel = frame.blob_voxel;
  const Prepared prepared = prepare(demand);
  io::keep_tiers(frame, [&](const io::ChunkDesc& c) { return tiers_needed(demand, prepared, c.bounds, c.layer, voxel); });
  drop_fine_parts(demand, frame);
}

void apply_demand(const ViewDemand& demand, io::FrameHeader& frame, std::vector<CellRead>& out) {
  out.clear();
  const Prepared prepared = prepare(demand);
  const std::vector<io::ChunkDesc>& chunks = frame.chunks;
  for (size_t first = 0; first < chunks.size();) {
    const size_t end = io::cell_end(chunks, first);
    CellRead cell;
    cell.box = chunks[first].bounds;
    cell.layer = chunks[first].layer;
    for (size_t c = first; c < end; ++c) cell.tiers_in_file |= uint16_t(1u << chunks[c].tier);
    cell.tiers_read = static_cast<uint8_t>(tiers_needed(demand, prepared, cell.box, cell.layer, frame.blob_voxel));
    cell.coarse = chunks[first].fine.split() && cell.tiers_read > 0 && coarse_enough(demand, cell.box, cell.layer);
    for (size_t c = first; c < end; ++c) frame.chunks[c].fine.dropped = cell.coarse;
    out.push_back(cell);
    first = end;
  }
  if (demand.everything()) return;
  size_t cell = 0;
  io::keep_tiers(frame, [&](const io::ChunkDesc&) { return out[cell++].tiers_read; });
}

bool short_of(const ViewDemand& demand, const std::vector<CellRead>& read, float blob_voxel) {
  const Prepared prepared = prepare(demand);
  for (const CellRead& cell : read) {
    if (cell.coarse && !coarse_enough(demand, cell.box, cell.layer) &&
        tiers_needed(demand, prepared, cell.box, cell.layer, blob_voxel) > 0) {
      return true;  // read coarse, now needed at full precision
    }
    if (cell.tiers_read >= io::kLodTiers) continue;
    const uint32_t need = tiers_needed(demand, prepared, cell.box, cell.layer, blob_voxel);
    if (need <= cell.tiers_read) continue;
    const uint32_t missing = ((1u << need) - 1u) & ~((1u << cell.tiers_read) - 1u);
    if (cell.tiers_in_file & missing) return true;
  }
  return false;
}

}  // namespace sluice::runtime
