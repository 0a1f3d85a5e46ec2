#include "generated_mesh_checks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace mtled::test {

TetMesh kernel_ready(TetMesh mesh) {
  remove_unused_nodes(mesh);
  check_mesh(mesh);
  return mesh;
}

double mesh_volume(const TetMesh& mesh) {
  double volume = 0.0;
  for (Index t = 0; t < mesh.tet_count(); ++t) volume += tet_volume(mesh, t);
  return volume;
}

double region_volume(const TetMesh& mesh, const std::string& region) {
  const auto it = std::find(mesh.region_names.begin(), mesh.region_names.end(), region);
  EXPECT_NE(it, mesh.region_names.end()) << "no region " << region;
  const auto r = static_cast<Index>(it - mesh.region_names.begin());
  double volume = 0.0;
  for (Index t = 0; t < mesh.tet_count(); ++t)
    if (mesh.tet_region[static_cast<std::size_t>(t)] == r) volume += tet_volume(mesh, t);
  return volume;
}

Bounds bounding_box(const TetMesh& mesh) {
  Bounds b{Vec3::Constant(INFINITY), Vec3::Constant(-INFINITY)};
  for (const Vec3& x : mesh.points) {
    b.min = b.min.cwiseMin(x);
    b.max = b.max.cwiseMax(x);
  }
  return b;
}

double longest_boundary_edge(const TetMesh& mesh) {
  double longest = 0.0;
  for (const auto& face : boundary_faces(mesh))
    for (int a = 0; a < 3; ++a) {
      const Vec3& p = mesh.points[static_cast<std::size_t>(face[static_cast<std::size_t>(a)])];
      const Vec3& q = mesh.points[static_cast<std::size_t>(face[static_cast<std::size_t>((a + 1) % 3)])];
      longest = std::max(longest, (p - q).norm());
    }
  return longest;
}

const std::vector<Index>& node_set(const TetMesh& mesh, const std::string& name) {
  static const std::vector<Index> empty;
  const auto it = mesh.node_sets.find(name);
  if (it == mesh.node_sets.end()) {
    ADD_FAILURE() << "no node set \"" << name << "\"";
    return empty;
  }
  EXPECT_FALSE(it->second.empty()) << "node set \"" << name << "\" is empty";
  return it->second;
}

Problem input_error(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& e) {
    if (!e.problems().empty()) return e.problems().front();
    ADD_FAILURE() << "InputError without problems";
    return {};
  }
  ADD_FAILURE() << "expected an InputError";
  return {};
}

double inscribed_deficit_bound(double longest_edge, double radius) {
  return longest_edge * longest_edge / (2.0 * radius * radius);
}

NeedlePath documented_needle_path(const Vec3& size, const Vec3& center) {
  return {center + Vec3(0.025 / 0.14 * size[0], 0.006 / 0.156 * size[1], 0.5 * size[2]), 0.11 / 0.14 * size[2]};
}

bool inside(const TetMesh& mesh, const Vec3& x) {
  for (const auto& tet : mesh.tets) {
    Mat3 edges;
    for (int k = 0; k < 3; ++k) edges.col(k) = mesh.points[tet[k + 1]] - mesh.points[tet[0]];
    const Vec3 b = edges.fullPivLu().solve(x - mesh.points[tet[0]]);
    if (b.minCoeff() >= -1e-12 && b.sum() <= 1 + 1e-12) return true;
  }
  return false;
}

bool identical(const TetMesh& a, const TetMesh& b) {
  return a.points == b.points && a.tets == b.tets && a.tet_region == b.tet_region && a.region_names == b.region_names &&
         a.node_sets == b.node_sets;
}

}  // namespace mtled::test
