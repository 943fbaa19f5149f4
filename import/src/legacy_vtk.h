// Private: legacy VTK files (.vtk, "# vtk DataFile Version x.y"), read by
// sluice itself.
//
// Every dataset type (POLYDATA, UNSTRUCTURED_GRID, STRUCTURED_GRID,
// STRUCTURED_POINTS, RECTILINEAR_GRID), ASCII and BINARY (big-endian), the
// cell formats before and after version 5.0, point, cell and field data with
// METADATA blocks. Every declared count is checked against the bytes that
// remain before anything is allocated or read, and every ASCII value is
// checked to be a number, so a file cut short, a count raised or a byte
// changed in a keyword gives an io::Error naming the file, the section, the
// array and what was expected against what was found. Binary sections that
// are not wanted are skipped without reading them.
//
// String and variant arrays (rare in particle output) are not decoded: such
// a file gives an error that says how to convert it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/types.h"

namespace sluice::import::detail {

struct LegacyRead {
  io::ParticleFrame frame;         // raw values: non-finite numbers are kept for the caller
  std::optional<double> time;  // from a TimeValue/TIME field-data array, if any
};

// The point-data arrays of the file, in file order. Reads the whole
// structure (binary data is skipped, not read).
std::vector<std::string> legacy_vtk_arrays(const std::string& path);

// Positions (as float), ids from `id_array` (if not empty) and the
// `attributes` (vectors as magnitudes). Cells other than vertices are
// ignored with a note in frame.repairs.
LegacyRead read_legacy_vtk(const std::string& path, const std::vector<std::string>& attributes,
                           const std::string& id_array);

}  // namespace sluice::import::detail
