#include "stl/stl_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <numeric>
#include <optional>
#include <sstream>
#include <tuple>

#include "mtled/errors.hpp"
#include "stl/self_intersection.hpp"

namespace mtled {

namespace {

constexpr const char* kRepairAdvice =
    "repair the surface (e.g. MeshLab: Filters > Cleaning and Repairing; Blender: 3D-Print toolbox) and export it "
    "again";

struct Facets {
  std::vector<std::array<Vec3, 3>> corners;
  std::vector<int> lines;  // ASCII only
};

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot be opened for reading: check its permissions");
  std::ostringstream content;
  content << in.rdbuf();
  return content.str();
}

bool equals_ignoring_case(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

// Whitespace-separated words of an ASCII STL with the line each starts on.
class StlWords {
 public:
  StlWords(const std::string& text, const std::filesystem::path& file) : text_(text), file_(file) {}

  bool done() {
    skip_space();
    return position_ >= text_.size();
  }
  int line() const { return line_; }
  std::string where() const { return fmt::format("{}:{}", file_.string(), line_); }

  std::string_view next(std::string_view expected_for_message) {
    if (done())
      throw InputError(
          where(), fmt::format("the file ends where \"{}\" was expected: the STL is cut off", expected_for_message));
    const std::size_t start = position_;
    while (position_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[position_]))) ++position_;
    return std::string_view(text_).substr(start, position_ - start);
  }

  void expect(std::string_view keyword) {
    const std::string_view word = next(keyword);
    if (!equals_ignoring_case(word, keyword))
      throw InputError(where(), fmt::format("expected \"{}\", found \"{}\": not a valid ASCII STL (facet normal .. "
                                            "outer loop, 3 x vertex x y z, endloop, endfacet)",
                                            keyword, shorten(word)));
  }

  double number() {
    const std::string_view word = next("a number");
    double value = 0.0;
    const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (error != std::errc() || end != word.data() + word.size() || !std::isfinite(value))
      throw InputError(where(), fmt::format("\"{}\" is not a finite number", shorten(word)));
    return value;
  }

  void skip_line() {
    while (position_ < text_.size() && text_[position_] != '\n') ++position_;
  }

 private:
  static std::string shorten(std::string_view word) {
    return word.size() > 40 ? std::string(word.substr(0, 40)) + "..." : std::string(word);
  }
  void skip_space() {
    while (position_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[position_]))) {
      if (text_[position_] == '\n') ++line_;
      ++position_;
    }
  }

  const std::string& text_;
  const std::filesystem::path& file_;
  std::size_t position_ = 0;
  int line_ = 1;
};

Facets parse_ascii(const std::string& text, const std::filesystem::path& file) {
  Facets facets;
  StlWords words(text, file);
  // One or more "solid NAME ... endsolid NAME" blocks.
  while (!words.done()) {
    words.expect("solid");
    words.skip_line();  // the name, possibly empty or several words
    while (true) {
      const std::string_view word = words.next("facet or endsolid");
      if (equals_ignoring_case(word, "endsolid")) {
        words.skip_line();
        break;
      }
      if (!equals_ignoring_case(word, "facet"))
        throw InputError(words.where(),
                         fmt::format("expected \"facet\" or \"endsolid\", found \"{}\"", word.substr(0, 40)));
      const int line = words.line();
      words.expect("normal");
      for (int k = 0; k < 3; ++k) words.number();  // recomputed from the corners; writers often leave it 0
      words.expect("outer");
      words.expect("loop");
      std::array<Vec3, 3> corners;
      for (auto& corner : corners) {
        words.expect("vertex");
        for (int k = 0; k < 3; ++k) corner[k] = words.number();
      }
      words.expect("endloop");
      words.expect("endfacet");
      facets.corners.push_back(corners);
      facets.lines.push_back(line);
    }
  }
  return facets;
}

Facets parse_binary(const std::string& data, const std::filesystem::path& file) {
  std::uint32_t count = 0;
  std::memcpy(&count, data.data() + 80, sizeof count);  // STL is little-endian, as is every target of mtled
  Facets facets;
  facets.corners.resize(count);
  for (std::uint32_t f = 0; f < count; ++f) {
    const char* record = data.data() + 84 + 50 * static_cast<std::size_t>(f) + 12;  // skip the normal
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        float value = 0.0f;
        std::memcpy(&value, record + 4 * (3 * c + k), sizeof value);
        if (!std::isfinite(value))
          throw InputError(fmt::format("{} (facet {})", file.string(), f + 1),
                           "has a coordinate that is not a finite "
                           "number: the file is damaged");
        facets.corners[f][static_cast<std::size_t>(c)][k] = value;
      }
  }
  return facets;
}

Facets parse(const std::filesystem::path& file) {
  const std::string data = read_file(file);
  // Binary: an 80-byte header, a facet count, 50 bytes per facet. The size decides, since binary headers
  // may start with "solid" too.
  if (data.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, data.data() + 80, sizeof count);
    if (data.size() == 84 + 50 * static_cast<std::size_t>(count)) return parse_binary(data, file);
  }
  const auto first = data.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && equals_ignoring_case(std::string_view(data).substr(first, 5), "solid"))
    return parse_ascii(data, file);
  throw InputError(file.string(),
                   "is not an STL file: neither ASCII (starting with \"solid\") nor binary (84 bytes "
                   "+ 50 per facet); export the surface as STL");
}

// Facets that share a corner share its index: corners with identical coordinates are merged (STL writers
// repeat a vertex's coordinates bit for bit). Vertices are numbered in order of first appearance, as Gmsh's
// own STL reader does.
void merge_corners(const Facets& facets, StlSurface& surface) {
  const std::size_t corners = 3 * facets.corners.size();
  if (corners == 0) return;
  auto corner = [&](std::size_t c) -> const Vec3& { return facets.corners[c / 3][c % 3]; };
  std::vector<std::size_t> order(corners);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Vec3 &x = corner(a), &y = corner(b);
    return std::lexicographical_compare(x.data(), x.data() + 3, y.data(), y.data() + 3);
  });
  // first[c]: the first corner (in file order) with the coordinates of corner c.
  std::vector<std::size_t> first(corners);
  for (std::size_t k = 0; k < corners; ++k)
    first[order[k]] = k > 0 && corner(order[k]) == corner(order[k - 1]) ? first[order[k - 1]] : order[k];
  std::vector<Index> index(corners, -1);
  surface.triangles.resize(facets.corners.size());
  for (std::size_t c = 0; c < corners; ++c) {
    if (index[first[c]] < 0) {
      index[first[c]] = static_cast<Index>(surface.vertices.size());
      surface.vertices.push_back(corner(c));
    }
    surface.triangles[c / 3][c % 3] = index[first[c]];
  }
}

void check_facets(const StlSurface& s) {
  if (s.triangles.size() < 4)
    throw InputError(s.file.string(),
                     fmt::format("has {} facets; a closed surface needs at least 4", s.triangles.size()));
  const Eigen::AlignedBox3d box = [&] {
    Eigen::AlignedBox3d b;
    for (const Vec3& v : s.vertices) b.extend(v);
    return b;
  }();
  const double scale = box.sizes().maxCoeff();
  for (std::size_t f = 0; f < s.triangles.size(); ++f) {
    const auto& t = s.triangles[f];
    const Vec3 &a = s.vertices[static_cast<std::size_t>(t[0])], &b = s.vertices[static_cast<std::size_t>(t[1])],
               &c = s.vertices[static_cast<std::size_t>(t[2])];
    // Zero area against the model's size (relative 1e-12: below that the facet is a round-off sliver).
    if ((b - a).cross(c - a).norm() <= 1e-12 * scale * scale)
      throw InputError(s.where(f),
                       fmt::format("facet has zero area (corners {}, {}, {} coincide or are collinear); "
                                   "remove degenerate facets or {}",
                                   fmt::format("({:.6g}, {:.6g}, {:.6g})", a[0], a[1], a[2]),
                                   fmt::format("({:.6g}, {:.6g}, {:.6g})", b[0], b[1], b[2]),
                                   fmt::format("({:.6g}, {:.6g}, {:.6g})", c[0], c[1], c[2]), kRepairAdvice));
  }
}

std::string point_text(const Vec3& x) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", x[0], x[1], x[2]); }

// Every edge in exactly two facets, traversed in opposite directions; all facets connected.
void check_closed_manifold(const StlSurface& s) {
  struct EdgeUse {
    Index low, high;
    std::size_t facet;
    bool forward;  // traversed low -> high
  };
  std::vector<EdgeUse> uses;
  uses.reserve(3 * s.triangles.size());
  for (std::size_t f = 0; f < s.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Index a = s.triangles[f][static_cast<std::size_t>(k)],
                  b = s.triangles[f][static_cast<std::size_t>((k + 1) % 3)];
      uses.push_back({std::min(a, b), std::max(a, b), f, a < b});
    }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return std::tie(x.low, x.high, x.facet) < std::tie(y.low, y.high, y.facet);
  });

  std::vector<std::size_t> piece(s.triangles.size());
  std::iota(piece.begin(), piece.end(), std::size_t{0});
  auto root = [&](std::size_t f) {
    while (piece[f] != f) f = piece[f] = piece[piece[f]];
    return f;
  };
  std::size_t open_edges = 0, crowded_edges = 0;
  std::optional<std::size_t> first_open, first_crowded, first_flipped;
  for (std::size_t begin = 0; begin < uses.size();) {
    std::size_t end = begin;
    while (end < uses.size() && uses[end].low == uses[begin].low && uses[end].high == uses[begin].high) ++end;
    if (end - begin == 1) {
      ++open_edges;
      if (!first_open) first_open = begin;
    } else if (end - begin > 2) {
      ++crowded_edges;
      if (!first_crowded) first_crowded = begin;
    } else {
      if (uses[begin].forward == uses[begin + 1].forward && !first_flipped) first_flipped = begin;
      piece[root(uses[begin].facet)] = root(uses[begin + 1].facet);
    }
    begin = end;
  }
  auto edge_text = [&](std::size_t use) {
    return fmt::format("{} - {}", point_text(s.vertices[static_cast<std::size_t>(uses[use].low)]),
                       point_text(s.vertices[static_cast<std::size_t>(uses[use].high)]));
  };
  if (open_edges > 0)
    throw InputError(s.where(uses[*first_open].facet),
                     fmt::format("the surface is not closed: {} edges belong to one facet only (the first, {}, to this "
                                 "facet); mtled meshes the volume inside a closed surface: close the holes, or {}",
                                 open_edges, edge_text(*first_open), kRepairAdvice));
  if (crowded_edges > 0)
    throw InputError(s.where(uses[*first_crowded].facet),
                     fmt::format("the surface is not a manifold: {} edges belong to more than two facets (the first, "
                                 "{}); remove duplicate or internal facets, or {}",
                                 crowded_edges, edge_text(*first_crowded), kRepairAdvice));
  if (first_flipped)
    throw InputError(
        s.where(uses[*first_flipped + 1].facet),
        fmt::format("facets are not consistently oriented: this facet and the one at {} run along edge {} in "
                    "the same direction; make all normals point outwards (MeshLab: Filters > Normals > "
                    "Re-Orient all faces coherently)",
                    s.where(uses[*first_flipped].facet), edge_text(*first_flipped)));
  std::size_t pieces = 0;
  for (std::size_t f = 0; f < piece.size(); ++f) pieces += root(f) == f ? 1 : 0;
  if (pieces > 1)
    throw InputError(s.file.string(),
                     fmt::format("the surface has {} separate closed pieces; mtled meshes one body from one closed "
                                 "surface: export each body to its own file, or join them into one surface",
                                 pieces));
}

void measure(StlSurface& s) {
  for (const auto& t : s.triangles) {
    const Vec3 &a = s.vertices[static_cast<std::size_t>(t[0])], &b = s.vertices[static_cast<std::size_t>(t[1])],
               &c = s.vertices[static_cast<std::size_t>(t[2])];
    s.volume += a.dot(b.cross(c)) / 6.0;  // divergence theorem, exact for a closed polyhedron
    s.area += 0.5 * (b - a).cross(c - a).norm();
  }
  s.volume = std::abs(s.volume);  // inward-facing normals give the same body
}

}  // namespace

std::string StlSurface::where(std::size_t facet) const {
  if (facet < facet_lines.size()) return fmt::format("{}:{}", file.string(), facet_lines[facet]);
  return fmt::format("{} (facet {})", file.string(), facet + 1);
}

StlSurface read_closed_stl(const std::filesystem::path& file, double scale) {
  StlSurface surface;
  surface.file = file;
  Facets facets = parse(file);
  if (facets.corners.empty()) throw InputError(file.string(), "has no facets: export a closed surface as STL");
  for (auto& corners : facets.corners)
    for (Vec3& corner : corners) corner *= scale;
  surface.facet_lines = std::move(facets.lines);
  merge_corners(facets, surface);
  check_facets(surface);
  check_closed_manifold(surface);
  if (const auto crossing = find_self_intersection(surface.vertices, surface.triangles))
    throw InputError(surface.where(crossing->first),
                     fmt::format("the surface intersects itself: this facet crosses the one at {} near {}; mtled "
                                 "meshes the inside of a surface that does not cross itself: {}",
                                 surface.where(crossing->second), point_text(crossing->near), kRepairAdvice));
  measure(surface);
  return surface;
}

}  // namespace mtled
