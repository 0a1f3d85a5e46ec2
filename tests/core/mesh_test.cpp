#include <gtest/gtest.h>

#include <algorithm>

#include "mtled/mesh.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

TEST(Mesh, BoxSurfaceAndVolume) {
  const TetMesh mesh = test::box_mesh(Vec3(2, 1, 1), 4, 3, 2);
  double volume = 0.0;
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    EXPECT_GT(tet_volume(mesh, t), 0.0);
    volume += tet_volume(mesh, t);
  }
  EXPECT_NEAR(volume, 2.0, 1e-12);
  const auto surface = surface_nodes(mesh);
  const int interior = (4 - 1) * (3 - 1) * (2 - 1);
  int on_surface = 0;
  for (char s : surface) on_surface += s;
  EXPECT_EQ(on_surface, mesh.node_count() - interior);
}

TEST(Mesh, BoundaryFacesPointOutwardAndCloseTheSurface) {
  const TetMesh mesh = test::box_mesh(Vec3(1, 2, 3), 3, 2, 4, 0.2);
  const auto faces = boundary_faces(mesh);
  EXPECT_EQ(faces.size(), 2u * 2 * (3 * 2 + 2 * 4 + 3 * 4));  // two triangles per boundary square
  Vec3 sum = Vec3::Zero();
  double area = 0.0;
  const Vec3 centre(0.5, 1.0, 1.5);
  for (const auto& f : faces) {
    const Vec3& a = mesh.points[f[0]];
    const Vec3 n = 0.5 * (mesh.points[f[1]] - a).cross(mesh.points[f[2]] - a);
    EXPECT_GT(n.dot(a - centre), 0.0);  // a convex body: outward normals point away from its centre
    sum += n;
    area += n.norm();
  }
  EXPECT_LT(sum.norm(), 1e-12);  // a closed surface
  EXPECT_NEAR(area, 2.0 * (1 * 2 + 2 * 3 + 1 * 3), 1e-12);
}

TEST(Mesh, BoundaryFacesOfInvertedTetsStillPointOutward) {
  // Every third tet's vertex order reversed (negative volume, as some files write them): the same faces, the same
  // outward order.
  const TetMesh mesh = test::box_mesh(Vec3(1, 2, 3), 3, 2, 4);
  TetMesh mixed = mesh;
  for (std::size_t t = 0; t < mixed.tets.size(); t += 3) std::swap(mixed.tets[t][0], mixed.tets[t][1]);
  ASSERT_LT(tet_volume(mixed, 0), 0.0);
  // Each face rotated to start at its smallest vertex (a rotation keeps the orientation), then sorted.
  auto normalised = [](std::vector<std::array<Index, 3>> faces) {
    for (auto& f : faces) std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    std::sort(faces.begin(), faces.end());
    return faces;
  };
  EXPECT_EQ(normalised(boundary_faces(mixed)), normalised(boundary_faces(mesh)));
}

TEST(Mesh, MeanEdgeLengthOfAUniformGrid) {
  // A cube of side h cut into 6 Kuhn tets has edges h (axes), h sqrt2 (face diagonals), h sqrt3 (main
  // diagonal): every node's mean lies between h and h sqrt3.
  const TetMesh mesh = test::box_mesh(Vec3(1, 1, 1), 5, 5, 5);
  for (double h : mean_edge_length_at_nodes(mesh)) {
    EXPECT_GE(h, 0.2 - 1e-12);
    EXPECT_LE(h, 0.2 * std::sqrt(3.0) + 1e-12);
  }
}

TEST(Mesh, CheckMeshFixesOrientationAndRefusesDegenerateTets) {
  TetMesh mesh = test::box_mesh(Vec3(1, 1, 1), 1, 1, 1);
  std::swap(mesh.tets[0][0], mesh.tets[0][1]);
  ASSERT_LT(tet_volume(mesh, 0), 0.0);
  check_mesh(mesh);
  EXPECT_GT(tet_volume(mesh, 0), 0.0);

  TetMesh flat = mesh;
  flat.tets[1] = {flat.tets[1][0], flat.tets[1][1], flat.tets[1][2], flat.tets[1][2]};
  flat.source = "flat.msh";
  try {
    check_mesh(flat);
    FAIL() << "a zero-volume tet was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "flat.msh");
    EXPECT_NE(std::string(e.what()).find("zero volume"), std::string::npos);
  }

  TetMesh inverted = mesh;
  std::swap(inverted.tets[2][0], inverted.tets[2][1]);
  EXPECT_THROW(check_mesh(inverted, /*fix_orientation=*/false), InputError);

  TetMesh out_of_range = mesh;
  out_of_range.tets[0][3] = 1000;
  EXPECT_THROW(check_mesh(out_of_range), InputError);
}

TEST(Mesh, CheckMeshRefusesFoldedAndRepeatedTets) {
  // A 3x3x3 box; its middle node moved through a neighbouring node's opposite face folds the tets around it.
  TetMesh mesh = test::box_mesh(Vec3(1, 1, 1), 3, 3, 3);
  ASSERT_NO_THROW(check_mesh(mesh));
  Index middle = -1;
  for (Index i = 0; i < mesh.node_count(); ++i)
    if ((mesh.points[i] - Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3)).norm() < 1e-12) middle = i;
  ASSERT_GE(middle, 0);
  TetMesh folded = mesh;
  folded.source = "folded.inp";
  folded.points[middle] = Vec3(0.9, 0.9, 0.9);  // past the nodes at 2/3
  try {
    check_mesh(folded);
    FAIL() << "a folded mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "folded.inp");
    EXPECT_NE(std::string(e.what()).find("lie on the same side of their shared face"), std::string::npos) << e.what();
  }
  TetMesh allowed = folded;
  EXPECT_NO_THROW(check_mesh(allowed, true, /*allow_overlaps=*/true));

  TetMesh repeated = mesh;
  repeated.tets.push_back(repeated.tets[5]);
  repeated.tet_region.push_back(0);
  EXPECT_THROW(check_mesh(repeated), InputError);

  // Mixed vertex orders without a fold are a file convention, not an error.
  TetMesh mixed = mesh;
  for (std::size_t t = 0; t < mixed.tets.size(); t += 3) std::swap(mixed.tets[t][0], mixed.tets[t][1]);
  EXPECT_NO_THROW(check_mesh(mixed));
}

TEST(Mesh, RemoveUnusedNodesKeepsOrderAndSets) {
  TetMesh mesh = test::box_mesh(Vec3(1, 1, 1), 1, 1, 1);
  mesh.points.insert(mesh.points.begin(), Vec3(9, 9, 9));  // an unused geometry point first
  for (auto& tet : mesh.tets)
    for (auto& v : tet) ++v;
  for (auto& [name, set] : mesh.node_sets)
    for (auto& v : set) ++v;
  mesh.node_sets["stray"] = {0};
  remove_unused_nodes(mesh);
  EXPECT_EQ(mesh.node_count(), 8);
  EXPECT_TRUE(mesh.node_sets["stray"].empty());
  EXPECT_EQ(mesh.node_sets["z0"].size(), 4u);
  check_mesh(mesh);
}

// A flat tet laid on two boundary triangles of the box's top face caps the surface as a mesher's sliver does on a
// curved one (its radius ratio 0, two faces on the boundary): it goes, and only it; the box alone loses nothing.
TEST(Mesh, RemoveBoundarySliversTakesTheCapAndNothingElse) {
  TetMesh mesh = test::box_mesh(Vec3(1.0, 1.0, 1.0), 3, 3, 3);
  const TetMesh original = mesh;
  EXPECT_EQ(remove_boundary_slivers(mesh), 0);
  std::vector<std::array<Index, 3>> top;
  for (const auto& face : boundary_faces(mesh))
    if (std::all_of(face.begin(), face.end(), [&](Index v) { return mesh.points[v].z() > 1.0 - 1e-12; }))
      top.push_back(face);
  // Two top triangles that share an edge (a, c): the cap is (a, b, c, d).
  std::array<Index, 4> cap{};
  bool found = false;
  for (std::size_t i = 0; i < top.size() && !found; ++i)
    for (std::size_t j = i + 1; j < top.size() && !found; ++j) {
      std::vector<Index> shared, other;
      for (Index v : top[i]) (std::count(top[j].begin(), top[j].end(), v) ? shared : other).push_back(v);
      if (shared.size() != 2) continue;
      const Index d =
          *std::find_if(top[j].begin(), top[j].end(), [&](Index v) { return v != shared[0] && v != shared[1]; });
      cap = {shared[0], other[0], shared[1], d};
      found = true;
    }
  ASSERT_TRUE(found);
  mesh.tets.push_back(cap);
  mesh.tet_region.push_back(0);
  EXPECT_LT(tet_radius_ratio(mesh, mesh.tet_count() - 1), kSliverRadiusRatio);
  EXPECT_EQ(remove_boundary_slivers(mesh), 1);
  EXPECT_EQ(mesh.tets, original.tets);
  EXPECT_EQ(mesh.tet_region, original.tet_region);
  EXPECT_EQ(mesh.node_sets, original.node_sets);
}

TEST(Mesh, SelectNodes) {
  const TetMesh mesh = test::box_mesh(Vec3(1, 1, 1), 3, 3, 3);
  const auto surface = surface_nodes(mesh);
  std::vector<Problem> problems;
  const auto plane = NodeSelector::parse({{"plane", {{"point", {0, 0, 1}}, {"normal", {0, 0, 1}}}}}, "/n", problems);
  EXPECT_EQ(select_nodes(*plane, mesh, surface, "/n").size(), 16u);
  const auto group = NodeSelector::parse({{"group", "z1"}}, "/n", problems);
  EXPECT_EQ(select_nodes(*group, mesh, surface, "/n"), select_nodes(*plane, mesh, surface, "/n"));
  const auto all = NodeSelector::parse({{"box", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}}, {"surface_only", true}}, "/n",
                                       problems);
  EXPECT_EQ(select_nodes(*all, mesh, surface, "/n").size(), 64u - 8u);
  const auto typo = NodeSelector::parse({{"group", "z2"}}, "/b/0/nodes", problems);
  try {
    select_nodes(*typo, mesh, surface, "/b/0/nodes");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "/b/0/nodes/group");
    EXPECT_NE(std::string(e.what()).find("did you mean"), std::string::npos);
  }
}

}  // namespace
}  // namespace mtled
