// Cell types of VTK unstructured grids (vtkCellType.h, "VTK File Formats" in the VTK User's Guide).
#include <fmt/format.h>

#include <algorithm>

#include "mtled/errors.hpp"
#include "mtled/io/vtk_grid.hpp"

namespace mtled::vtk {

namespace {

constexpr long long kTetra = 10;

enum class CellKind { tetra, other_volume, lower_dimension, unknown };

// clang-format off
CellKind cell_kind(long long type) {
  switch (type) {
    case kTetra: return CellKind::tetra;
    // 0 empty, 1 vertex, 2 poly-vertex, 3 line, 4 poly-line, 5 triangle, 6 strip, 7 polygon, 8 pixel, 9 quad,
    // 21-23, 28, 30, 34-36 quadratic and cubic curves and surfaces, 60-63, 68-70, 75-77 higher-order ones.
    case 0: case 1: case 2: case 3: case 4: case 5: case 6: case 7: case 8: case 9:
    case 21: case 22: case 23: case 28: case 30: case 34: case 35: case 36:
    case 60: case 61: case 62: case 63: case 68: case 69: case 70: case 75: case 76: case 77:
      return CellKind::lower_dimension;
    // 11 voxel, 12 hexahedron, 13 wedge, 14 pyramid, 15-16 prisms, 24 quadratic tetra, 25-27, 29, 31-33, 37
    // quadratic volumes, 41 convex point set, 42 polyhedron, 64-67, 71-74, 78-81 higher-order volumes.
    case 11: case 12: case 13: case 14: case 15: case 16: case 24: case 25: case 26: case 27: case 29:
    case 31: case 32: case 33: case 37: case 41: case 42: case 64: case 65: case 66: case 67:
    case 71: case 72: case 73: case 74: case 78: case 79: case 80: case 81:
      return CellKind::other_volume;
    default: return CellKind::unknown;
  }
}
// clang-format on

}  // namespace

bool ArrayRequest::wants_cell(const std::string& name) const {
  return std::find(cell_arrays.begin(), cell_arrays.end(), name) != cell_arrays.end();
}

bool ArrayRequest::wants_point(const std::string& name) const {
  return std::find(point_arrays.begin(), point_arrays.end(), name) != point_arrays.end();
}

void add_cells(UnstructuredGrid& grid, std::span<const long long> ends, std::span<const long long> connectivity,
               std::span<const long long> types, std::size_t first_point, std::size_t piece_points,
               const std::function<std::string(std::size_t)>& where) {
  if (ends.size() != types.size())
    throw InputError(where(0),
                     fmt::format("the grid has {} cell types but {} cells: the file is damaged; save it again",
                                 types.size(), ends.size()));
  long long begin = 0;
  for (std::size_t c = 0; c < types.size(); ++c) {
    const long long end = ends[c];
    if (end < begin || end > static_cast<long long>(connectivity.size()))
      throw InputError(where(c), fmt::format("cell {} has offset {}, outside {}..{}: the offsets are damaged", c, end,
                                             begin, connectivity.size()));
    const long long type = types[c];
    switch (cell_kind(type)) {
      case CellKind::lower_dimension:
        break;
      case CellKind::unknown:
        throw InputError(where(c), fmt::format("cell {} has type {}, which is not a VTK cell type mtled knows: mtled "
                                               "reads tetrahedra (type 10) and skips vertices, lines and surface "
                                               "cells",
                                               c, type));
      case CellKind::other_volume:
        throw InputError(where(c),
                         fmt::format("cell {} has type {}{}: mtled needs a mesh of linear 4-node tetrahedra (VTK type "
                                     "10); re-mesh with tets only, or convert (ParaView: Tetrahedralize filter)",
                                     c, type,
                                     type == 24 ? " (10-node quadratic tetra)"
                                                : " (a volume cell other than a "
                                                  "4-node tetra)"));
      case CellKind::tetra: {
        if (end - begin != 4)
          throw InputError(
              where(c), fmt::format("cell {} is a tetra (type 10) but lists {} points instead of 4", c, end - begin));
        std::array<Index, 4> tet{};
        for (std::size_t k = 0; k < 4; ++k) {
          const long long v = connectivity[static_cast<std::size_t>(begin) + k];
          if (v < 0 || v >= static_cast<long long>(piece_points))
            throw InputError(where(c), fmt::format("cell {} refers to point {}, but there are only {} points "
                                                   "(numbered from 0): the file is damaged; save it again",
                                                   c, v, piece_points));
          tet[k] = static_cast<Index>(first_point + static_cast<std::size_t>(v));
        }
        grid.tets.push_back(tet);
        grid.tet_cell.push_back(grid.cell_count + c);
        break;
      }
    }
    begin = end;
  }
  grid.cell_count += types.size();
}

}  // namespace mtled::vtk
