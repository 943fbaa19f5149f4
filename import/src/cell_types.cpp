// VTK's cell type names (vtkCellType.h) for messages.
#include "cell_types.h"

#include <utility>

namespace sluice::import::detail {


std::string cell_type_name(int64_t type) {
  static const std::pair<int, const char*> kNames[] = {
      {1, "VERTEX"},          {2, "POLY_VERTEX"},          {3, "LINE"},
      {4, "POLY_LINE"},       {5, "TRIANGLE"},             {6, "TRIANGLE_STRIP"},
      {7, "POLYGON"},         {8, "PIXEL"},                {9, "QUAD"},
      {10, "TETRA"},          {11, "VOXEL"},               {12, "HEXAHEDRON"},
      {13, "WEDGE"},          {14, "PYRAMID"},             {15, "PENTAGONAL_PRISM"},
      {16, "HEXAGONAL_PRISM"}, {21, "QUADRATIC_EDGE"},     {22, "QUADRATIC_TRIANGLE"},
      {23, "QUADRATIC_QUAD"}, {24, "QUADRATIC_TETRA"},     {25, "QUADRATIC_HEXAHEDRON"},
      {26, "QUADRATIC_WEDGE"}, {27, "QUADRATIC_PYRAMID"},  {42, "POLYHEDRON"},
      {68, "LAGRANGE_CURVE"}, {69, "LAGRANGE_TRIANGLE"},   {70, "LAGRANGE_QUADRILATERAL"},
      {71, "LAGRANGE_TETRAHEDRON"}, {72, "LAGRANGE_HEXAHEDRON"}, {73, "LAGRANGE_WEDGE"}};
  for (const auto& [id, name] : kNames) {
    if (id == type) return name;
  }
  return "type " + std::to_string(type);
}

std::vector<std::string> non_vertex_names(const std::set<int64_t>& types) {
  std::vector<std::string> names;
  for (const int64_t t : types) {
    if (!is_vertex_cell(t)) names.push_back(cell_type_name(t));
  }
  return names;
}

std::string ignored_cells_note(const std::vector<std::string>& names, uint64_t points) {
  if (names.empty()) return {};
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  return "cells of type " + list + " ignored: using the " + std::to_string(points) + " points as particles";
}

}  // namespace sluice::import::detail
