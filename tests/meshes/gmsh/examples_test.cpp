// Every generator's documented example block loads (examples are what `mtled plugins --describe` shows).
#include <gtest/gtest.h>

#include "generated_mesh_checks.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "test_support.hpp"

namespace mtled::test {
namespace {

class GmshGeneratorExample : public ::testing::TestWithParam<std::string> {};

TEST_P(GmshGeneratorExample, LoadsAndHitsItsTarget) {
  const std::string name = GetParam();
  const json example = catalog().load(Category::mesh, name).example();
  ASSERT_TRUE(example.contains("target_nodes")) << "examples stay small through target_nodes";
  const auto folder = scratch_dir("gmsh_example_" + name);
  if (name == "stl_surface") {
    // The example names an STL in the scene's folder: a 40 mm octahedron in millimetres stands in for it.
    const std::string corners[6] = {"20 0 0", "-20 0 0", "0 20 0", "0 -20 0", "0 0 20", "0 0 -20"};
    const int faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    std::string stl = "solid octahedron\n";
    for (const auto& f : faces)
      stl += "facet normal 0 0 0\nouter loop\nvertex " + corners[f[0]] + "\nvertex " + corners[f[1]] + "\nvertex " +
             corners[f[2]] + "\nendloop\nendfacet\n";
    write_text(folder / example.at("path").get<std::string>(), stl + "endsolid octahedron\n");
  }
  const TetMesh mesh = kernel_ready(make<MeshSource>(name, example)->load(MeshContext{folder, 1, {}}));
  const double target = example.at("target_nodes").get<double>();
  EXPECT_NEAR(mesh.node_count(), target, 0.03 * target);
}

INSTANTIATE_TEST_SUITE_P(AllGenerators, GmshGeneratorExample,
                         ::testing::Values("box", "cylinder", "layered_cylinder", "brain_phantom", "stl_surface"));

}  // namespace
}  // namespace mtled::test
