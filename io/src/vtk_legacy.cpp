// Legacy VTK reader: "# vtk DataFile Version x.y", ASCII or BINARY, DATASET UNSTRUCTURED_GRID ("VTK File
// Formats", VTK User's Guide; version 5.x writes cells as OFFSETS and CONNECTIVITY arrays). In a binary file
// each array's values follow its header line as big-endian numbers of the type the header names; the
// keywords and headers stay text.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "mtled/errors.hpp"
#include "mtled/io/text_cursor.hpp"
#include "mtled/io/vtk_grid.hpp"

namespace mtled::vtk {

namespace {

using mesh_readers::TextCursor;

bool is_hex(char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'); }

int hex_value(char c) { return c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10; }

// VTK writes spaces in array names as "%20" (and other special characters as %xx).
std::string array_name(std::string_view name) {
  std::string result;
  for (std::size_t i = 0; i < name.size(); ++i) {
    if (name[i] == '%' && i + 2 < name.size() && is_hex(name[i + 1]) && is_hex(name[i + 2])) {
      result += static_cast<char>(hex_value(name[i + 1]) * 16 + hex_value(name[i + 2]));
      i += 2;
    } else {
      result += name[i];
    }
  }
  return result;
}

// "SPACE=LPS" or "SPACE=RAS" in the title line: 3D Slicer's record of the frame its coordinates are in.
std::string coordinate_system_tag(std::string_view title) {
  const auto at = title.find("SPACE=");
  if (at == std::string_view::npos) return "";
  const std::string value = mesh_readers::uppercase(title.substr(at + 6, 3));
  return value == "LPS" || value == "RAS" ? value : "";
}

enum class Location { none, points, cells };

class LegacyParser {
 public:
  LegacyParser(const mesh_readers::MeshFileText& file, const ArrayRequest& request)
      : cursor_(file.text, file.label), request_(request) {}

  UnstructuredGrid parse() {
    read_header();
    while (const auto token = cursor_.next_token()) {
      const std::string keyword = mesh_readers::uppercase(*token);
      if (keyword == "POINTS")
        read_points();
      else if (keyword == "CELLS")
        read_cells();
      else if (keyword == "CELL_TYPES")
        read_cell_types();
      else if (keyword == "CELL_DATA")
        start_attributes(Location::cells);
      else if (keyword == "POINT_DATA")
        start_attributes(Location::points);
      else if (keyword == "SCALARS")
        read_scalars();
      else if (keyword == "FIELD")
        read_field();
      else if (keyword == "VECTORS" || keyword == "NORMALS")
        skip_attribute(keyword, 3);
      else if (keyword == "TENSORS")
        skip_attribute(keyword, 9);
      else if (keyword == "TENSORS6")
        skip_attribute(keyword, 6);
      else if (keyword == "GLOBAL_IDS" || keyword == "PEDIGREE_IDS")
        skip_attribute(keyword, 1);
      else if (keyword == "TEXTURE_COORDINATES")
        skip_texture_coordinates();
      else if (keyword == "COLOR_SCALARS")
        skip_color_scalars();
      else if (keyword == "LOOKUP_TABLE")
        skip_lookup_table();
      else if (keyword == "METADATA")
        skip_metadata();
      else
        cursor_.fail(
            fmt::format("unexpected {} in a legacy VTK unstructured grid: expected POINTS, CELLS, "
                        "CELL_TYPES, CELL_DATA, POINT_DATA or a data array; the file is damaged or a count "
                        "before this line is wrong",
                        mesh_readers::quote_token(*token)));
    }
    if (!have_points_ || !have_cells_ || !have_types_)
      throw InputError(cursor_.where(), fmt::format("the file ends without {}: it is truncated or holds no "
                                                    "unstructured grid; save it again",
                                                    !have_points_  ? "POINTS"
                                                    : !have_cells_ ? "CELLS"
                                                                   : "CELL_TYPES"));
    return std::move(grid_);
  }

 private:
  void read_header() {
    const auto first = cursor_.next_line();
    const std::string_view magic = "# vtk DataFile Version";
    if (!first || mesh_readers::lowercase(first->substr(0, magic.size())) != mesh_readers::lowercase(magic))
      cursor_.fail(fmt::format("a legacy .vtk file starts with \"{} x.y\", found {}: is this a VTK file?", magic,
                               mesh_readers::quote_token(first ? *first : "")));
    const auto version = mesh_readers::parse_real(mesh_readers::trim(first->substr(magic.size())));
    // Clamped: a damaged version such as 5e59 does not fit in an int (undefined behaviour; found by tests/fuzz).
    major_version_ = version ? static_cast<int>(std::clamp(*version, 0.0, 1000.0)) : 0;
    const auto title = cursor_.next_line();
    if (!title) cursor_.fail("the file ends after its first line: it is truncated");
    grid_.coordinate_system = coordinate_system_tag(*title);
    const auto format = cursor_.next_line();
    if (!format) cursor_.fail("the file ends before its ASCII/BINARY line: it is truncated");
    const std::string kind = mesh_readers::uppercase(mesh_readers::trim(*format));
    binary_ = kind == "BINARY";
    if (kind != "ASCII" && !binary_)
      cursor_.fail(fmt::format("the third line of a legacy .vtk file is ASCII or BINARY, found {}",
                               mesh_readers::quote_token(kind)));
    const auto dataset = cursor_.expect_token("the DATASET line");
    if (mesh_readers::uppercase(dataset) != "DATASET")
      cursor_.fail(fmt::format("expected DATASET UNSTRUCTURED_GRID, found {}", mesh_readers::quote_token(dataset)));
    const auto type = mesh_readers::uppercase(cursor_.expect_token("the dataset type"));
    if (type != "UNSTRUCTURED_GRID")
      cursor_.fail(
          fmt::format("the dataset is {}: mtled reads tetrahedral meshes, stored as UNSTRUCTURED_GRID; "
                      "convert it (ParaView: Tetrahedralize, then save)",
                      type));
  }

  // The rest of the keyword's line, split; `count` fields expected at least.
  const std::vector<std::string_view>& header(std::string_view keyword, std::size_t count, std::string_view form) {
    const auto rest = cursor_.next_line();
    mesh_readers::split_whitespace(rest ? *rest : std::string_view(), fields_);
    if (fields_.size() < count) cursor_.fail(fmt::format("{} needs \"{} {}\" on its line", keyword, keyword, form));
    return fields_;
  }

  // a * b for counts read from the file, which a damaged header may make as large as it likes: saturated
  // instead of overflowing (no file holds that many values, so reading them then fails at the file's end).
  static long long product(long long a, long long b) {
    long long result = 0;
    return __builtin_mul_overflow(a, b, &result) ? std::numeric_limits<long long>::max() : result;
  }

  long long count(std::string_view token, std::string_view what) {
    const auto value = mesh_readers::to_integer(token, cursor_, what);
    if (value < 0) cursor_.fail(fmt::format("{} cannot be negative", what));
    return value;
  }

  void read_points() {
    if (have_points_) cursor_.fail("a second POINTS section: mtled reads one grid per file");
    header("POINTS", 2, "n dataType");
    const auto n = count(fields_[0], "the number of points");
    if (binary_) {
      std::vector<double> xyz;
      read_binary(product(n, 3), fields_[1], "POINTS", [&](double v) { xyz.push_back(v); });
      for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) grid_.points.push_back({xyz[i], xyz[i + 1], xyz[i + 2]});
      have_points_ = true;
      return;
    }
    grid_.points.reserve(cursor_.reservable(n, 6));  // "0 0 0 " at least
    for (long long i = 0; i < n; ++i) {
      Vec3 x;
      for (int d = 0; d < 3; ++d) {
        const auto token = cursor_.next_token();
        if (!token) cursor_.fail_at_end(fmt::format("POINTS (point {} of {})", i, n));
        x[d] = mesh_readers::to_real(*token, cursor_, "a point coordinate");
      }
      grid_.points.push_back(x);
    }
    have_points_ = true;
  }

  void read_cells() {
    if (!have_points_) cursor_.fail("CELLS comes before POINTS: mtled needs the points first; save the file again");
    if (have_cells_) cursor_.fail("a second CELLS section: mtled reads one grid per file");
    header("CELLS", 2, major_version_ >= 5 ? "nOffsets nConnectivity" : "n size");
    const auto first = count(fields_[0], "the number of cells");
    const auto second = count(fields_[1], "the size of the cell list");
    const long cells_line = cursor_.line();
    if (major_version_ >= 5) {
      // OFFSETS dataType / nOffsets integers from 0 / CONNECTIVITY dataType / nConnectivity integers
      std::vector<long long> offsets;
      read_integers(first, offsets, "OFFSETS", expect_keyword("OFFSETS"));
      read_integers(second, connectivity_, "CONNECTIVITY", expect_keyword("CONNECTIVITY"));
      if (offsets.empty() || offsets.front() != 0)
        throw InputError(cursor_.where(cells_line), "OFFSETS must start with 0: the file is damaged; save it again");
      ends_.assign(offsets.begin() + 1, offsets.end());
      cell_line_.assign(ends_.size(), cells_line);
    } else if (binary_) {
      read_counted_cells(first, second, cells_line);
    } else {
      // n lines "k i1 ... ik", `second` integers in all.
      ends_.reserve(cursor_.reservable(first, 2));
      long long read = 0;
      for (long long c = 0; c < first; ++c) {
        const auto k = count(cell_token(c, first), "the number of points of a cell");
        cell_line_.push_back(cursor_.line());
        if (k >= second - read)  // read + 1 + k > second, without overflowing for a huge k
          cursor_.fail(
              fmt::format("the cells list more than the {} integers announced on line {}: the file is "
                          "damaged; save it again",
                          second, cells_line));
        read += 1 + k;
        for (long long j = 0; j < k; ++j)
          connectivity_.push_back(mesh_readers::to_integer(cell_token(c, first), cursor_, "a point index"));
        ends_.push_back(static_cast<long long>(connectivity_.size()));
      }
      if (read != second)
        throw InputError(cursor_.where(cells_line), fmt::format("CELLS announces {} integers but its {} cells hold {}: "
                                                                "the file is damaged; save it again",
                                                                second, first, read));
    }
    have_cells_ = true;
  }

  std::string_view cell_token(long long c, long long n) {
    const auto token = cursor_.next_token();
    if (!token) cursor_.fail_at_end(fmt::format("CELLS (cell {} of {})", c, n));
    return *token;
  }

  // A binary file's version 4 cells: `total` integers, each cell its point count k and then k indices.
  void read_counted_cells(long long cells, long long total, long cells_line) {
    std::vector<long long> list;
    read_integers(total, list, "CELLS", "int");
    std::size_t at = 0;
    for (long long c = 0; c < cells; ++c) {
      if (at >= list.size() || list[at] < 0 || list[at] >= static_cast<long long>(list.size() - at))
        throw InputError(cursor_.where(cells_line),
                         fmt::format("cell {} of {} lists more points than CELLS holds integers ({}): the file is "
                                     "damaged; save it again",
                                     c, cells, total));
      connectivity_.insert(connectivity_.end(), list.begin() + static_cast<std::ptrdiff_t>(at + 1),
                           list.begin() + static_cast<std::ptrdiff_t>(at + 1 + list[at]));
      at += 1 + static_cast<std::size_t>(list[at]);
      ends_.push_back(static_cast<long long>(connectivity_.size()));
    }
    if (at != list.size())
      throw InputError(cursor_.where(cells_line), fmt::format("CELLS announces {} integers but its {} cells hold {}: "
                                                              "the file is damaged; save it again",
                                                              total, cells, at));
    cell_line_.assign(ends_.size(), cells_line);
  }

  // "KEYWORD dataType": returns the data type.
  std::string expect_keyword(std::string_view keyword) {
    const auto token = cursor_.expect_token(keyword);
    if (mesh_readers::uppercase(token) != keyword)
      cursor_.fail(fmt::format("expected {} (VTK 5 cell layout), found {}", keyword, mesh_readers::quote_token(token)));
    const auto rest = cursor_.next_line();
    return std::string(mesh_readers::trim(rest ? *rest : std::string_view()));
  }

  void read_integers(long long n, std::vector<long long>& values, std::string_view what, std::string_view type) {
    if (binary_) {
      read_binary(n, type, what, [&](double v) {
        if (v != std::floor(v) || std::abs(v) > 9.0e15)
          cursor_.fail(fmt::format("{} holds {}, not an integer: the file is damaged; save it again", what, v));
        values.push_back(static_cast<long long>(v));
      });
      return;
    }
    values.reserve(cursor_.reservable(n, 2));  // a digit and a space at least
    for (long long i = 0; i < n; ++i)
      values.push_back(mesh_readers::to_integer(cursor_.expect_token(what), cursor_, "an integer"));
  }

  void read_cell_types() {
    if (!have_cells_) cursor_.fail("CELL_TYPES comes before CELLS: save the file again");
    header("CELL_TYPES", 1, "n");
    const auto n = count(fields_[0], "the number of cell types");
    if (n != static_cast<long long>(ends_.size()))
      cursor_.fail(fmt::format("CELL_TYPES announces {} cells but CELLS has {}: the file is damaged; save it again", n,
                               ends_.size()));
    std::vector<long long> types;
    read_integers(n, types, "CELL_TYPES", "int");
    add_cells(grid_, ends_, connectivity_, types, 0, grid_.points.size(),
              [this](std::size_t c) { return cursor_.where(cell_line_[c]); });
    connectivity_ = {};
    ends_ = {};
    have_types_ = true;
  }

  void start_attributes(Location location) {
    header(location == Location::cells ? "CELL_DATA" : "POINT_DATA", 1, "n");
    const auto n = count(fields_[0], "the number of tuples");
    const std::size_t expected = location == Location::cells ? grid_.cell_count : grid_.points.size();
    if ((location == Location::cells && !have_types_) || (location == Location::points && !have_points_))
      cursor_.fail("attribute data comes before the grid it belongs to: save the file again");
    if (n != static_cast<long long>(expected))
      cursor_.fail(fmt::format("{} announces {} values but the grid has {} {}: the file is damaged; save it again",
                               location == Location::cells ? "CELL_DATA" : "POINT_DATA", n, expected,
                               location == Location::cells ? "cells" : "points"));
    location_ = location;
    tuples_ = n;
  }

  void require_attributes(std::string_view keyword) {
    if (location_ == Location::none)
      cursor_.fail(fmt::format("{} outside CELL_DATA or POINT_DATA: the file is damaged; save it again", keyword));
  }

  // Reads `n` numbers into a new array of the current location when it is wanted, else skips them.
  void read_array(std::string name, int components, long long tuples, std::string_view type, long header_line) {
    const bool cells = location_ == Location::cells;
    const bool wanted = location_ != Location::none && (cells ? request_.wants_cell(name) : request_.wants_point(name));
    DataArray array{std::move(name), components, {}, cursor_.where(header_line)};
    const long long n = product(tuples, components);
    const std::string what = fmt::format("the values of array \"{}\" ({} expected)", array.name, n);
    if (binary_) {
      read_binary(n, type, what, [&](double v) {
        if (wanted) array.values.push_back(v);
      });
    } else {
      if (wanted) array.values.reserve(cursor_.reservable(n, 2));  // a digit and a space at least
      for (long long i = 0; i < n; ++i) {
        const auto token = cursor_.expect_token(what);
        if (wanted) array.values.push_back(mesh_readers::to_real(token, cursor_, "an array value"));
      }
    }
    if (location_ == Location::none) return;
    (cells ? grid_.cell_arrays : grid_.point_arrays).push_back(std::move(array));
  }

  void read_scalars() {
    require_attributes("SCALARS");
    header("SCALARS", 2, "dataName dataType [numComp]");
    std::string name = array_name(fields_[0]);
    const std::string type(fields_[1]);
    int components = 1;
    if (fields_.size() >= 3) {
      const auto c = mesh_readers::to_integer(fields_[2], cursor_, "the number of components");
      if (c < 1 || c > 4) cursor_.fail("SCALARS have 1 to 4 components");
      components = static_cast<int>(c);
    }
    const long line = cursor_.line();
    // The LOOKUP_TABLE line is optional in practice (the format requires it).
    const auto mark = cursor_.mark();
    const auto next = cursor_.next_token();
    if (next && mesh_readers::uppercase(*next) == "LOOKUP_TABLE") {
      cursor_.next_line();
    } else {
      cursor_.reset(mark);
    }
    read_array(std::move(name), components, tuples_, type, line);
  }

  void read_field() {
    header("FIELD", 2, "dataName numArrays");
    const auto arrays = count(fields_[1], "the number of arrays");
    for (long long a = 0; a < arrays; ++a) {
      auto name = cursor_.expect_token("a FIELD array header \"name numComponents numTuples dataType\"");
      if (mesh_readers::uppercase(name) == "METADATA") {  // VTK 9 writes one after an array
        skip_metadata();
        name = cursor_.expect_token("a FIELD array header \"name numComponents numTuples dataType\"");
      }
      const long line = cursor_.line();
      const auto rest = cursor_.next_line();
      mesh_readers::split_whitespace(rest ? *rest : std::string_view(), fields_);
      if (fields_.size() < 3)
        cursor_.fail(fmt::format("a FIELD array needs \"name numComponents numTuples dataType\", found {}",
                                 mesh_readers::quote_token(name)));
      const auto components = count(fields_[0], "the number of components");
      const auto tuples = count(fields_[1], "the number of tuples");
      if (components < 1 || components > 1000) cursor_.fail(fmt::format("an array with {} components", components));
      if (location_ != Location::none && tuples != tuples_)
        cursor_.fail(fmt::format("array {} has {} tuples but the grid has {}: the file is damaged; save it again",
                                 mesh_readers::quote_token(name), tuples, tuples_));
      read_array(array_name(name), static_cast<int>(components), tuples, fields_[2], line);
    }
  }

  // Attributes mtled does not use: `components` numbers per tuple.
  void skip_attribute(const std::string& keyword, int components) {
    require_attributes(keyword);
    header(keyword, 2, "dataName dataType");
    skip_values(product(tuples_, components), fields_[1]);
  }

  void skip_texture_coordinates() {
    require_attributes("TEXTURE_COORDINATES");
    header("TEXTURE_COORDINATES", 3, "dataName dim dataType");
    skip_values(product(tuples_, count(fields_[1], "the dimension")), fields_[2]);
  }

  void skip_color_scalars() {
    require_attributes("COLOR_SCALARS");
    header("COLOR_SCALARS", 2, "dataName nValues");
    skip_values(product(tuples_, count(fields_[1], "the number of values")), "unsigned_char");
  }

  void skip_lookup_table() {
    header("LOOKUP_TABLE", 2, "tableName size");
    skip_values(product(4, count(fields_[1], "the table size")), "unsigned_char");
  }

  // METADATA blocks (VTK 9 writers) end at an empty line.
  void skip_metadata() {
    cursor_.next_line();
    while (const auto line = cursor_.next_line())
      if (mesh_readers::trim(*line).empty()) return;
  }

  // `n` values of `type` (in a binary file; ASCII values are tokens whatever their type).
  void skip_values(long long n, std::string_view type) {
    if (binary_) return read_binary(n, type, "the values of a data array", [](double) {});
    for (long long i = 0; i < n; ++i) cursor_.expect_token("the values of a data array");
  }

  // The `n` big-endian values of `type` that follow a header line in a binary file, each passed to `sink`.
  template <class Sink>
  void read_binary(long long n, std::string_view type, std::string_view what, Sink&& sink) {
    const auto scalar = legacy_scalar_type(type);
    if (!scalar)
      cursor_.fail(fmt::format("{} holds binary values of type {}: mtled reads the numeric types (float, double, "
                               "int, ...); save the mesh as ASCII legacy VTK or as .vtu",
                               what, mesh_readers::quote_token(type)));
    const auto bytes = n <= 0 ? std::optional<std::string_view>("")
                              : (static_cast<unsigned long long>(n) > (1ULL << 40) / scalar->size
                                     ? std::nullopt
                                     : cursor_.next_bytes(static_cast<std::size_t>(n) * scalar->size));
    if (!bytes) cursor_.fail_at_end(what);
    const auto* data = reinterpret_cast<const unsigned char*>(bytes->data());
    for (long long i = 0; i < n; ++i) {
      const double v = decode_scalar(data + static_cast<std::size_t>(i) * scalar->size, *scalar, true);
      if (!std::isfinite(v)) cursor_.fail(fmt::format("{} holds a value that is not a finite number", what));
      sink(v);
    }
  }

  TextCursor cursor_;
  const ArrayRequest& request_;
  UnstructuredGrid grid_;
  int major_version_ = 0;
  bool binary_ = false;
  bool have_points_ = false, have_cells_ = false, have_types_ = false;
  std::vector<long long> ends_, connectivity_;
  std::vector<long> cell_line_;
  Location location_ = Location::none;
  long long tuples_ = 0;
  std::vector<std::string_view> fields_;
};

}  // namespace

UnstructuredGrid read_legacy_vtk(const mesh_readers::MeshFileText& file, const ArrayRequest& request) {
  return LegacyParser(file, request).parse();
}

}  // namespace mtled::vtk
