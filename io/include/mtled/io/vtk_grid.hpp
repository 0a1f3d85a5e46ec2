#pragma once
// What the two VTK parsers (legacy .vtk, XML .vtu) hand to VtkFileReader: the tets of an unstructured
// grid and the data arrays it asked for.
#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mtled/types.hpp"
#include "mtled/io/mesh_file.hpp"

namespace mtled::vtk {

// A point or cell data array. `values` is filled only for the arrays the reader asked for (one value per
// tuple and component, row by row); the others are listed by name, for messages.
struct DataArray {
  std::string name;
  int components = 1;
  std::vector<double> values;
  std::string where;  // "file:line" of its header
};

struct ArrayRequest {
  std::vector<std::string> cell_arrays;
  std::vector<std::string> point_arrays;
  bool wants_cell(const std::string& name) const;
  bool wants_point(const std::string& name) const;
};

struct UnstructuredGrid {
  std::vector<Vec3> points;
  std::vector<std::array<Index, 4>> tets;
  std::vector<std::size_t> tet_cell;  // the cell each tet is, for cell arrays
  std::size_t cell_count = 0;
  std::vector<DataArray> cell_arrays;
  std::vector<DataArray> point_arrays;
  std::string coordinate_system;  // "LPS" or "RAS" when the file says (3D Slicer's "SPACE"), else empty
  std::string length_unit;        // "mm" in an mtled result written in millimetres ("LENGTH_UNIT"), else empty
};

// Adds the cells of one piece: 4-node tets (VTK_TETRA = 10) are kept, vertices, lines and surface cells are
// skipped, other volume cells refused. `ends[c]` is one past the last entry of cell c in `connectivity`;
// indices are into the piece's points, which start at `first_point` in grid.points. `where(c)` places
// cell c in the file for messages.
void add_cells(UnstructuredGrid& grid, std::span<const long long> ends, std::span<const long long> connectivity,
               std::span<const long long> types, std::size_t first_point, std::size_t piece_points,
               const std::function<std::string(std::size_t)>& where);

// How a binary array stores its values. XML names ("Float64", "Int32", ...) and legacy names ("double",
// "int", "vtktypeint64", ...) map to these.
enum class ScalarKind { signed_integer, unsigned_integer, real };
struct ScalarType {
  ScalarKind kind;
  std::size_t size;
};
std::optional<ScalarType> xml_scalar_type(std::string_view name);
std::optional<ScalarType> legacy_scalar_type(std::string_view name);
// The value of `type` stored at `data` in the given byte order, as a double (integers up to 2^53 exactly).
double decode_scalar(const unsigned char* data, ScalarType type, bool big_endian);

UnstructuredGrid read_legacy_vtk(const mesh_readers::MeshFileText& file, const ArrayRequest& request);
UnstructuredGrid read_vtu(const mesh_readers::MeshFileText& file, const ArrayRequest& request);

// Metres per unit of the grid's lengths: 1e-3 for an mtled result written in millimetres (LENGTH_UNIT "mm"), 1 when
// the file gives no unit; another unit is an InputError naming `label`.
double metres_per_length_unit(const UnstructuredGrid& grid, const std::string& label);

}  // namespace mtled::vtk
