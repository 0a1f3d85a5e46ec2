#pragma once
// The partition of a scene's cloud between ranks: METIS splits the background tets (the dual graph, tets adjacent
// when they share a face) into parts of equal tet counts with the fewest cut faces, and gives each node a part. The
// mpi backend and the partition study (benchmarks/partition_study.cpp) share it.
#include <span>
#include <vector>

#include "mtled/mesh.hpp"
#include "mtled/gradient_rows.hpp"

namespace mtled {

struct MeshPartition {
  std::vector<int> tet_part;   // per tet
  std::vector<int> node_part;  // per node: the part that sums its force
};

// Throws std::runtime_error when METIS fails. One part: every tet and node in part 0.
MeshPartition partition_mesh(const TetMesh& mesh, int parts);

// Per tet: how near its part's boundary it lies, in edges of the mesh from the nearest node another part owns (0:
// the tet has such a node), `layers` for every tet that far or farther. Numbering a part's points layer by layer
// puts those whose supports reach other parts' nodes (a support spans a node spacing or two) near the front.
std::vector<int> boundary_layers(const TetMesh& mesh, const MeshPartition& partition, int layers);

// Whether integration point p's support reaches a node that another part than `part` owns: a boundary point.
inline bool reaches_another_part(const GradientRows& rows, Index p, std::span<const int> node_part, int part) {
  for (int k = 0; k < rows.size(p); ++k)
    if (node_part[static_cast<std::size_t>(rows.node(p, k))] != part) return true;
  return false;
}

// Per part: its integration points, its ghost nodes (nodes its points' supports reach that another part owns), the
// nodes it owns, its boundary points (those whose supports reach a ghost node), and its neighbours (the parts owning
// its ghost nodes).
struct PartSizes {
  std::vector<std::int64_t> points, ghost_nodes, owned_nodes, boundary_points;
  std::vector<int> neighbours;
};
// `point_part[p]`: the part of integration point p; `rows`: the points' supports.
PartSizes part_sizes(const MeshPartition& partition, std::span<const int> point_part, const GradientRows& rows);

}  // namespace mtled
