// sluice/io/up_axis.h: which way is up in a simulation's output.
//
// Solvers do not say: gravity is -z in some, -y in others. `sluice convert`
// finds it from the data, in this order of trust:
//   1. motion: under gravity the fluid's top falls toward a floor that stays
//      (the trailing face of the fluid, seen from the direction of fall, moves
//      along it), over the first frames;
//   2. pressure: a resting fluid's pressure (or density) grows with depth;
//   3. shape: a resting fluid lies in a layer, thinnest along up (the sign is
//      then assumed positive);
// and stores the answer with how it was found (format 1.2, docs/format.md).
// Plain functions over small summaries; no state, any thread.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::io {

// A signed world axis. Unstated: a file older than format 1.2 (read as +z).
enum class UpAxis : uint8_t { Unstated = 0, PosX = 1, PosY = 2, PosZ = 3, NegX = 4, NegY = 5, NegZ = 6 };

// How the up axis of a file was found.
enum class UpEvidence : uint8_t {
  Unstated = 0,  // a file older than format 1.2
  Given = 1,     // --up
  Motion = 2,    // the fluid falls along -up over the first frames
  Pressure = 3,  // pressure or density grows along -up
  Shape = 4,     // the fluid lies flat, thinnest along up (sign assumed +)
  Default = 5,   // nothing in the data told: +z
};

int up_axis_index(UpAxis up);                  // 0 x, 1 y, 2 z (Unstated: 2)
bool up_axis_negative(UpAxis up);              // -x, -y, -z
std::array<float, 3> up_vector(UpAxis up);     // unit vector (Unstated: +z)
std::string up_axis_name(UpAxis up);           // "+y", "-z"; "+z" for Unstated
const char* up_evidence_name(UpEvidence e);    // "given", "motion", ...
UpAxis up_axis_from(int axis, bool negative);
// "x", "+x", "-x", "X", ... Returns nullopt for anything else.
std::optional<UpAxis> parse_up_axis(std::string_view text);

// A frame's shape: its extent, robust to spray (the 0.5% and 99.5%
// quantiles of each coordinate, from at most 65,536 evenly strided
// particles), and per axis the lowest and highest coordinate in each column
// along that axis of a grid over a box (NaN: empty column).
inline constexpr int kShapeColumns = 32;  // most cells along an axis
struct ShapeGrid {
  Aabb box;            // frame 0's bounds, so that frames compare column by column
  float cell = 0;      // smallest cell side: 2 particle spacings, so that a column is never empty by chance
  std::array<int, 3> cells() const;  // along each axis: box extent / cell, 1..kShapeColumns
};
struct FrameShape {
  uint64_t particles = 0;
  std::array<float, 3> low{}, high{};
  std::array<std::vector<float>, 3> column_low, column_high;  // empty without a grid
};
// `grid`: nullptr or an empty box: no columns.
FrameShape measure_shape(std::span<const float> xyz, const ShapeGrid* grid = nullptr);

struct UpFinding {
  UpAxis up = UpAxis::PosZ;
  UpEvidence evidence = UpEvidence::Default;
  std::string reason;  // one sentence with the figures, for the user
};

// From the shapes of the first frames, frame 0 first (at least two with
// particles and columns). For each of the six directions, how far the
// columns' trailing ends (the top, for a fall along -z) moved along it, the
// median over the columns filled in frame 0 and the later frame; the fall
// must reach half a spacing (`spacing`, world units) and three times any
// other direction's, and the columns' leading ends (the floor) must move
// less than a third of it: a fluid moving as a whole (sway, drift, free fall)
// is not evidence. nullopt: no clear fall.
// Frames of fewer than kLeastShapeParticles particles, or with no extent,
// are left out.
std::optional<UpFinding> up_from_motion(std::span<const FrameShape> first_frames, float spacing);
inline constexpr uint64_t kLeastShapeParticles = 64;

// From a pressure-like array (pressure or density: both grow with depth at
// rest) of one frame: a linear fit against position whose gradient lies
// within 25 degrees of an axis and explains at least 20% of the variance
// (a field without that trend explains about 3/n).
std::optional<UpFinding> up_from_pressure(std::span<const float> xyz, std::span<const float> values,
                                          std::string_view array_name);

// From a frame's shape: the thinnest extent, under half of each other one.
std::optional<UpFinding> up_from_shape(const FrameShape& shape);

// The arrays up_from_pressure can use, best first (pressure before density),
// that are present in `arrays`. Empty if none.
std::string pick_pressure_array(std::span<const std::string> arrays);

}  // namespace sluice::io
