// Private: checks of VTK XML files before VTK's reader sees them.
//
// VTK's XML readers allocate what a header declares (NumberOfPoints times
// the components) before they look at the data. These checks read the
// markup up to the appended data and the header of every data block (a few
// bytes each, wherever the block lies), and compare, for every DataArray
// whose length the file declares:
//   - the bytes its type, components and tuple count make, against the size
//     its block header states (raw or base64, plain or compressed), and
//   - the block's extent against the bytes present (appended data and
//     inline base64), or the values present (inline ascii).
// and, for cell lists (which VTK sizes by their last offset), that the last
// offset equals the connectivity's length (for zlib blocks only the last
// sub-block is inflated). The types array of an unstructured grid is read
// whole (one byte per cell) for the kinds of cells. A mismatch throws io::Error naming the file, the
// section and the array with both figures. Other compressed contents are not
// inflated: zlib reports a damaged stream itself, through VTK.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace sluice::import::detail {

// What the checks learn on the way: the kinds of cells, so that VTK's
// reader need not read the cells at all (vtk_reader.h).
struct XmlFacts {
  std::set<int64_t> cell_types;         // unstructured grids: every value of the types arrays
  std::vector<std::string> cell_lists;  // polydata: LINES, POLYGONS, TRIANGLE_STRIPS when not empty

  // The names of the cells that are not vertices, for the repair note.
  std::vector<std::string> non_vertex_cells() const;
};

// A .vtu or .vtp file.
XmlFacts check_vtk_xml(const std::string& path);

// A .pvtu or .pvtp file: its pieces must be .vtu/.vtp files inside the
// header's folder (no absolute paths, no '..' out of it, no other parallel
// header), must exist, and each passes check_vtk_xml. Returns the pieces;
// `facts` gathers theirs.
std::vector<std::string> check_parallel_xml(const std::string& path, XmlFacts& facts);

}  // namespace sluice::import::detail
