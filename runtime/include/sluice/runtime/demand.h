// sluice/runtime/demand.h: what the views draw of a frame, as LOD tiers per
// cell (format 1.4, io/lod.h), so a reader reads only that.
//
// The renderer keeps a particle when some view's frustum holds its splat
// and, with continuous LOD, when u >= 1 - level^(1/w): w = c * d_ref / d is
// its importance (c in 0.3..1 from its distance to the screen centre, d its
// distance to the eye; render/lod.h). For a cell (the records of one
// chunk's tiers) the largest w any point of its box can have bounds what it
// can keep, and io::tiers_for_keep() turns that into a tier count. The
// bound is conservative: a cell never gets fewer tiers than the renderer's
// per-particle test can keep from it, for any view the margin allows.
//
// A plain value type and pure functions: the renderer builds a demand from
// its views and options (stream/src/demand.cpp), the pipeline applies it to every
// frame it reads (Pipeline::set_demand), tests compare both with the cull.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "sluice/io/format.h"

namespace sluice::runtime {

// One eye or camera: column-major 4x4 matrices, as render::View holds them.
struct DemandView {
  std::array<float, 16> view{};        // world -> eye space (right-handed, looking down -z)
  std::array<float, 16> projection{};  // eye -> Vulkan clip space: perspective, any depth convention
  // The viewport's size in pixels (precision by distance measures in
  // them); 0: unknown, and records are read at full precision.
  uint32_t width = 0, height = 0;
};

struct ViewDemand {
  // The views the frames are drawn for (1 to 4; stereo: both eyes). Empty:
  // no view is known: every tier of every cell is read (the default), or
  // with `lod` a uniform level (uniform()).
  io::InlineVector<DemandView, 4> views;
  // Continuous LOD by the stable LOD value. false: every tier of each
  // visible cell (LOD off, or a random term the file's tiers do not order:
  // the position hash).
  bool lod = false;
  float level = 1;               // 0..1, the renderer's LOD level
  float reference_distance = 1;  // d_ref in world units (> 0): importance 1 at this distance
  // World units a particle's splat reaches beyond its centre: its radius,
  // times the largest growth in density-preserving LOD.
  float particle_reach = 0;
  float particle_radius = 0;     // the radius blobs' splats are sized from (render: blob_sigma)
  // How far (world units) the views may move before a frame read now is
  // drawn: boxes grow by it for the frustum and the distance tests.
  float margin = 0;
  // Precision by distance (format 3.0, io::ChunkDesc::fine): a record is
  // read without its fine part when that moves none of its particles more
  // than this many pixels in any view (coarse_enough()). 0: always read
  // whole.
  float position_error_pixels = 0;

  // Without views, a demand with `lod` and a level below 1 keeps that
  // fraction of every cell at importance 1 (io/particles.h's rule: scripts,
  // exports); any other demand without views reads everything.
  bool everything() const { return views.size() == 0 && !(lod && level < 1); }
  static ViewDemand uniform(float level) {
    ViewDemand d;
    d.lod = true;
    d.level = level;
    return d;
  }
};

// Tiers (0 .. io::kLodTiers) of a cell with box `box` and layer `layer` the
// demand needs: 0 when no view can see any splat of it; io::kLodTiers
// without LOD and when no view is known. Blobs follow the particles' rule
// with their own reach (their tiers hold their random term,
// io::blob_lod_uniform). `blob_voxel` is the frame's
// (io::FrameHeader::blob_voxel), for the blobs' reach.
uint32_t tiers_needed(const ViewDemand& demand, const io::Aabb& box, io::Layer layer, float blob_voxel);

// The most the coarse precision may move a particle, as a share of its
// radius (ViewDemand::particle_radius): what is left out never changes the
// fluid's depth by more than this share of a splat.
inline constexpr float kCoarseSplatShare = 0.25f;
// Whether a record of box `box` may be drawn at the coarse precision
// (format 3.0: its fine part left out) for every view of the demand: its
// particles then lie within demand.position_error_pixels of where the
// full precision puts them on every view's screen, for any view the margin
// allows, and within kCoarseSplatShare of a particle's radius. Conservative:
// false without views, for views of unknown pixel size, and for a box the
// eye may reach. Blobs (`layer`) are always read whole: their random term
// hashes the voxel their centroid lies in, which the coarse fill may change.
bool coarse_enough(const ViewDemand& demand, const io::Aabb& box, io::Layer layer);

// Keeps, of each cell of `frame`, the tiers the demand needs (io::keep_tiers),
// and marks the fine parts coarse_enough() leaves out (ChunkDesc::fine.dropped).
void apply_demand(const ViewDemand& demand, io::FrameHeader& frame);

// What a frame read under a demand holds of each of its cells, so that a
// later demand can be checked against it (Pipeline::short_of): one entry per
// cell of the whole frame, read or not.
struct CellRead {
  io::Aabb box;
  io::Layer layer = io::Layer::All;
  uint16_t tiers_in_file = 0;  // bit t: the file has a record of tier t for this cell
  uint8_t tiers_read = 0;     // the demand's tier count when read (tiers below it are present)
  bool coarse = false;        // read without its fine parts (the file has them: format 3.0)
};
// Records `frame`'s cells (before the demand drops any) with the tiers the
// demand reads of each into `out` (cleared first; no allocation once it
// has held as many cells), then applies the demand to `frame`.
void apply_demand(const ViewDemand& demand, io::FrameHeader& frame, std::vector<CellRead>& out);
// Whether `demand` needs a tier of some cell that `read` lacks, or the
// full precision of a cell read coarse.
bool short_of(const ViewDemand& demand, const std::vector<CellRead>& read, float blob_voxel);

}  // namespace sluice::runtime
