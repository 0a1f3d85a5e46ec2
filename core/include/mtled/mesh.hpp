#pragma once
// A tetrahedral mesh as read or generated: its vertices become the field nodes and its tets the background
// integration cells. Regions (physical volume groups, ELSETs) pick materials; node sets (physical surface
// groups, NSETs) pick boundary conditions.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "mtled/node_selector.hpp"
#include "mtled/types.hpp"

namespace mtled {

struct TetMesh {
  std::vector<Vec3> points;
  std::vector<std::array<Index, 4>> tets;
  std::vector<Index> tet_region;          // index into region_names, one per tet
  std::vector<std::string> region_names;  // at least one ("all" when the source has none)
  std::map<std::string, std::vector<Index>> node_sets;
  std::string source;  // file path or generator description, for messages
  // The frame the coordinates are in when the file records it ("LPS" or "RAS": 3D Slicer's "SPACE"), else
  // empty. Results carry it on, so that Slicer places them where the mesh was.
  std::string coordinate_system;
  // What a generator measured while making it (meshing time, the size it chose), for summary.json's "mesh".
  std::map<std::string, double> statistics;

  Index node_count() const { return static_cast<Index>(points.size()); }
  Index tet_count() const { return static_cast<Index>(tets.size()); }
};

// Signed volume of tet `t` (positive when its vertices are ordered right-handed).
double tet_volume(const TetMesh& mesh, Index t);
// The mean of tet `t`'s vertices.
Vec3 tet_centroid(const TetMesh& mesh, Index t);
// The four points of the symmetric degree-2 quadrature rule in tet `t` (each weighs a quarter of its volume), all
// inside it: barycentric (a, b, b, b) and its permutations.
std::array<Vec3, 4> tet_quadrature_points(const TetMesh& mesh, Index t);
// The smallest axis-aligned box holding the points (which must not be empty): lower and upper corners.
std::pair<Vec3, Vec3> bounding_box(const std::vector<Vec3>& points);

// Drops vertices no tet uses (Gmsh files carry geometry points and surface-only nodes), renumbers, keeps
// node sets restricted to the surviving nodes.
void remove_unused_nodes(TetMesh& mesh);

// Checks the mesh: at least one tet, finite coordinates, indices in range, no zero-volume tets. Tets listed
// with a negative volume are reordered when `fix_orientation` (a file's vertex-order convention), otherwise
// reported. Then no two tets may overlap: two tets on the same side of their shared face (one was inverted
// by a node moved through the opposite face; reordering would hide the fold) or a face shared by more than
// two tets are refused unless `allow_overlaps` (test clouds jittered at random, where only the nodes
// matter). Throws InputError naming `mesh.source`.
void check_mesh(TetMesh& mesh, bool fix_orientation = true, bool allow_overlaps = false);

// The boundary faces (faces used by exactly one tet), ordered so that (b - a) x (c - a) points out of the body.
std::vector<std::array<Index, 3>> boundary_faces(const TetMesh& mesh);

// Per-node flag: 1 if the node lies on a boundary face.
std::vector<char> surface_nodes(const TetMesh& mesh);

// The worst tet's shape (a regular tet has 70.53 degrees and 1): the smallest dihedral angle (degrees) and the smallest
// radius ratio 3 r_in / r_circ over all tets.
struct MeshQuality {
  double min_dihedral_angle_deg = 0.0;
  double min_radius_ratio = 0.0;
};
MeshQuality mesh_quality(const TetMesh& mesh);
// Tet t's radius ratio 3 r_in / r_circ: 1 for a regular tet, towards 0 for a sliver, 0 when flat.
double tet_radius_ratio(const TetMesh& mesh, Index t);

// A tet whose radius ratio is under this is a sliver: nearly flat, its volume no measure of the material's.
constexpr double kSliverRadiusRatio = 0.1;

// Removes the slivers that cap the boundary: tets under kSliverRadiusRatio with two or more faces on it, which a mesher
// leaves on a curved surface (all four vertices on the surface, so no move of an inner vertex mends them). Each goes
// with the volume it held, a mesh's smallest, and its inner faces become boundary; repeated until none is left (a
// neighbour may become a cap). Node sets and regions keep their nodes; returns the number removed.
Index remove_boundary_slivers(TetMesh& mesh);

// Per-node mean length of the mesh edges that meet at the node.
std::vector<double> mean_edge_length_at_nodes(const TetMesh& mesh);

// Nodes chosen by a selector. Throws InputError (at `pointer`) for an unknown group, listing the groups.
std::vector<Index> select_nodes(const NodeSelector& selector, const TetMesh& mesh,
                                const std::vector<char>& surface, const std::string& pointer);

}  // namespace mtled
