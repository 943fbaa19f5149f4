// Private: reading one VTK file with VTK's own readers (compiled only when
// sluice is built with VTK).
//
// Handles XML .vtu/.vtp and the multi-piece .pvtu/.pvtp (all pieces
// concatenated); legacy .vtk files are sluice's own (legacy_vtk.h). Errors that VTK reports through its output window are
// captured per thread and thrown as io::Error carrying VTK's message.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::import::detail {

// The point-data arrays a file offers (only the header is parsed).
std::vector<std::string> vtk_arrays(const std::string& path);

struct VtkRead {
  io::ParticleFrame frame;               // raw values: non-finite numbers are kept for the caller
  std::optional<double> time;        // from a TimeValue/TIME field-data array, if any
};

// Reads positions (as float), ids from `id_array` (if not empty) and the
// `attributes` (vectors as magnitudes). Cells are not read: those the
// checks found (`non_vertex_cells`, XmlFacts) are named in a note in
// frame.repairs. Throws io::Error naming the file.
VtkRead read_vtk(const std::string& path, const std::vector<std::string>& attributes, const std::string& id_array,
                 const std::vector<std::string>& non_vertex_cells);

}  // namespace sluice::import::detail
