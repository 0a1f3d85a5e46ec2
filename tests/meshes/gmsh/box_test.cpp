#include <gtest/gtest.h>

#include <omp.h>

#include <chrono>

#include "generated_mesh_checks.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "test_support.hpp"

namespace mtled::test {
namespace {

TetMesh load_box(const json& block) {
  auto source = make<MeshSource>("box", block);
  return kernel_ready(source->load(MeshContext{}));
}

TEST(GmshBox, HitsTheTargetNodeCountAndTheExactVolume) {
  const Vec3 size(0.03, 0.02, 0.01), origin(0.1, -0.2, 0.3);
  const auto start = std::chrono::steady_clock::now();
  const TetMesh mesh = load_box(
      {{"size", {size[0], size[1], size[2]}}, {"origin", {origin[0], origin[1], origin[2]}}, {"target_nodes", 2000}});
  RecordProperty("seconds",
                 std::to_string(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()));
  RecordProperty("nodes", mesh.node_count());
  RecordProperty("tets", mesh.tet_count());
  EXPECT_NEAR(mesh.node_count(), 2000, 0.03 * 2000);
  // Flat faces are meshed exactly: only round-off separates the tets' volume from a * b * c.
  EXPECT_NEAR(mesh_volume(mesh), size.prod(), 1e-9 * size.prod());
  EXPECT_EQ(mesh.region_names, std::vector<std::string>{"all"});
}

// Gmsh sets the process-wide OpenMP thread count when it initialises; the generator must give it back, or the
// solver that runs after the mesh is built would silently run on one thread.
TEST(GmshBox, LeavesTheOpenMpThreadCountAsItFoundIt) {
  omp_set_num_threads(3);
  (void)load_box({{"size", {0.01, 0.01, 0.01}}, {"target_nodes", 300}});
  EXPECT_EQ(omp_get_max_threads(), 3);
}

TEST(GmshBox, FaceNodeSetsLieOnTheirFaces) {
  const Vec3 size(0.03, 0.02, 0.01), origin(0.1, -0.2, 0.3);
  const TetMesh mesh = load_box(
      {{"size", {size[0], size[1], size[2]}}, {"origin", {origin[0], origin[1], origin[2]}}, {"target_nodes", 800}});
  const std::vector<char> surface = surface_nodes(mesh);
  const char* const names[3][2] = {{"x0", "x1"}, {"y0", "y1"}, {"z0", "z1"}};
  std::vector<char> on_some_face(mesh.points.size(), 0);
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const double plane = origin[axis] + side * size[axis];
      const auto& set = node_set(mesh, names[axis][side]);
      // Nodes of a planar OCC face are placed on it up to round-off of the coordinates (~1e-16 m here).
      for (const Index n : set) {
        EXPECT_NEAR(mesh.points[static_cast<std::size_t>(n)][axis], plane, 1e-12) << names[axis][side];
        on_some_face[static_cast<std::size_t>(n)] = 1;
      }
      // ... and every node on that plane belongs to the set.
      std::size_t on_plane = 0;
      for (const Vec3& x : mesh.points) on_plane += std::abs(x[axis] - plane) <= 1e-12 ? 1 : 0;
      EXPECT_EQ(set.size(), on_plane) << names[axis][side];
    }
  // The six sets together are exactly the boundary nodes.
  EXPECT_EQ(on_some_face, surface);
}

TEST(GmshBox, MeshSizeIsUsedDirectlyAndTargetIgnored) {
  const TetMesh coarse = load_box({{"size", {0.02, 0.02, 0.02}}, {"mesh_size", 0.004}, {"target_nodes", 100000}});
  const TetMesh fine = load_box({{"size", {0.02, 0.02, 0.02}}, {"mesh_size", 0.002}});
  // Halving h multiplies the node count by about 8 in the volume and 4 on the faces: between 4 and 8.
  // At h = 4 mm a 20 mm cube has some 5^3 = 125 nodes, far from the 100,000 target.
  EXPECT_LT(coarse.node_count(), 1000);
  const double ratio = static_cast<double>(fine.node_count()) / coarse.node_count();
  EXPECT_GT(ratio, 3.5);
  EXPECT_LT(ratio, 8.5);
  // The boundary edges stay near h: none longer than twice mesh_size.
  EXPECT_LT(longest_boundary_edge(coarse), 2 * 0.004);
}

TEST(GmshBox, IsDeterministic) {
  const json block = {{"size", {0.03, 0.02, 0.01}}, {"target_nodes", 1000}};
  EXPECT_TRUE(identical(load_box(block), load_box(block)));
}

TEST(GmshBox, RejectsNonPositiveSize) {
  const Problem problem = input_error([] { make<MeshSource>("box", {{"size", {0.03, 0.0, 0.01}}}); });
  EXPECT_EQ(problem.where, "/test/size");
  EXPECT_NE(problem.message.find("at least 1e-05 m"), std::string::npos) << problem.message;
}

TEST(GmshBox, RefusesAMeshSizeThatWouldTakeHours) {
  // A 1 m cube at 1 mm is about 10^9 / 1.6 nodes: refused before Gmsh starts.
  auto source = make<MeshSource>("box", {{"size", {1.0, 1.0, 1.0}}, {"mesh_size", 0.001}});
  const Problem problem = input_error([&] { source->load(MeshContext{}); });
  EXPECT_EQ(problem.where, "/test/mesh_size");
  EXPECT_NE(problem.message.find("larger mesh_size"), std::string::npos) << problem.message;
}

}  // namespace
}  // namespace mtled::test
