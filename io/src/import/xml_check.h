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
// sub-block is inflated). A mismatch throws io::Error naming the file, the
// section and the array with both figures. Other compressed contents are not
// inflated: zlib reports a damaged stream itself, through VTK.
#pragma once

#include <string>
#include <vector>

namespace sluice::io::detail {

// A .vtu or .vtp file.
void check_vtk_xml(const std::string& path);

// A .pvtu or .pvtp file: its pieces must be .vtu/.vtp files inside the
// header's folder (no absolute paths, no '..' out of it, no other parallel
// header), must exist, and each passes check_vtk_xml. Returns the pieces.
std::vector<std::string> check_parallel_xml(const std::string& path);

}  // namespace sluice::io::detail
