#pragma once
// Reading an STL file (ASCII or binary) into a closed triangulated surface, with the checks that tell a
// user what to fix before Gmsh sees the surface: mtled parses the file itself rather than letting Gmsh guess
// its format (gmsh::merge would also run a .geo script given by mistake).
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

struct StlSurface {
  std::filesystem::path file;
  std::vector<Vec3> vertices;                   // merged: facets that share a corner share its index
  std::vector<std::array<Index, 3>> triangles;  // in file order
  std::vector<int> facet_lines;                 // line of each facet in an ASCII file; empty for binary
  double volume = 0.0;                          // enclosed volume (m^3), > 0
  double area = 0.0;                            // m^2

  // "file:line" (ASCII) or "file (facet k)" (binary, k from 1) for messages about one facet.
  std::string where(std::size_t facet) const;
};

// Reads `file` and scales its coordinates by `scale`. Throws InputError naming the file (and line) when it
// is not an STL file, has a degenerate facet, is not closed, is not a 2-manifold, is inconsistently
// oriented, has more than one piece, or intersects itself.
StlSurface read_closed_stl(const std::filesystem::path& file, double scale);

}  // namespace mtled
