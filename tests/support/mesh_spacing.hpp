#pragma once
// The spacing of a mesh where a predicate holds: for tests of mesh sources' refinement.
#include <vector>

#include "mtled/mesh.hpp"

namespace mtled::test {

// The mean edge length at the nodes where `where(x)` holds, and how many nodes that is.
struct Spacing {
  double mean = 0.0;
  int nodes = 0;
};
template <class Where>
Spacing spacing_where(const TetMesh& mesh, Where&& where) {
  const std::vector<double> spacing = mean_edge_length_at_nodes(mesh);
  Spacing s;
  for (std::size_t n = 0; n < mesh.points.size(); ++n)
    if (where(mesh.points[n])) {
      s.mean += spacing[n];
      ++s.nodes;
    }
  if (s.nodes > 0) s.mean /= s.nodes;
  return s;
}

}  // namespace mtled::test
