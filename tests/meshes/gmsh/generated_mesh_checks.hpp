#pragma once
// Measurements of generated meshes shared by the Gmsh generator tests.
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/mesh.hpp"

namespace mtled::test {

// The mesh as the kernel sees it after load(): unused nodes dropped, checked, tets oriented.
TetMesh kernel_ready(TetMesh mesh);

// Sum of the (positive) tet volumes.
double mesh_volume(const TetMesh& mesh);
// Sum of the tet volumes of one region.
double region_volume(const TetMesh& mesh, const std::string& region);

struct Bounds {
  Vec3 min, max;
};
Bounds bounding_box(const TetMesh& mesh);

// Longest edge of a boundary face: the chord length that bounds how far the faceted surface lies from a
// curved one (for vertices on a surface of curvature radius >= R, at most L^2 / (4 R) while L <= R).
double longest_boundary_edge(const TetMesh& mesh);

// The node set, failing the test when it is missing or empty.
const std::vector<Index>& node_set(const TetMesh& mesh, const std::string& name);

// The first problem of the InputError that `action` throws; fails the test when it throws none.
Problem input_error(const std::function<void()>& action);

// The meshed body is a polyhedron inscribed in the cylinder: its side faces are triangles with vertices on
// the curved face. Projected on the base plane, a face with edges <= L covers a chord of the circle no
// longer than L, so it lies at most the sagitta s = R - sqrt(R^2 - L^2/4) <= L^2 / (4 R) inside the circle.
// The missing volume is at most the annulus 2 pi R s H: a relative deficit of at most L^2 / (2 R^2).
double inscribed_deficit_bound(double longest_edge, double radius);

// The brain phantom's documented needle path: x = cx + 0.025/0.14 sx, y = cy + 0.006/0.156 sy, entering at
// the top z = cz + sz/2 and inside the body for 110/140 sz below it.
struct NeedlePath {
  Vec3 entry;
  double depth_inside;
};
NeedlePath documented_needle_path(const Vec3& size, const Vec3& center);

// True when `x` lies in some tet (barycentric coordinates >= -1e-12, round-off of the solve). Brute force.
bool inside(const TetMesh& mesh, const Vec3& x);

// True when both meshes have identical points (bit for bit), tets, regions and node sets.
bool identical(const TetMesh& a, const TetMesh& b);

}  // namespace mtled::test
