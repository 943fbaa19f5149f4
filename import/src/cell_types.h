// Private: VTK's cell types by name, for the note on files whose cells are
// not vertices (their points still become particles). The same names VTK's
// enum has (vtkCellType.h), without needing VTK.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace sluice::import::detail {

// "TETRA" for 10, "type 77" for a number without a name here.
std::string cell_type_name(int64_t type);

// True for the cells a particle file may hold: empty (0), VERTEX (1) and
// POLY_VERTEX (2).
inline bool is_vertex_cell(int64_t type) { return type >= 0 && type <= 2; }

// The names of `types` that are not vertex cells, in increasing order.
std::vector<std::string> non_vertex_names(const std::set<int64_t>& types);

// The repair note for `points` points whose cells (named) were ignored;
// empty when `names` is.
std::string ignored_cells_note(const std::vector<std::string>& names, uint64_t points);

}  // namespace sluice::import::detail
