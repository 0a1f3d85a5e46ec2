#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "generated_mesh_checks.hpp"
#include "mesh_spacing.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "test_support.hpp"

namespace mtled::test {
namespace {

TetMesh load(const std::string& generator, const json& block) {
  auto source = make<MeshSource>(generator, block);
  return kernel_ready(source->load(MeshContext{}));
}

TEST(GmshCylinder, NodeCountVolumeAndFaces) {
  const double r = 0.015, h = 0.017;
  const Vec3 base(0.01, -0.02, 0.005);
  const TetMesh mesh = load(
      "cylinder", {{"radius", r}, {"height", h}, {"base_center", {base[0], base[1], base[2]}}, {"target_nodes", 2500}});
  EXPECT_NEAR(mesh.node_count(), 2500, 0.03 * 2500);
  const double exact = std::numbers::pi * r * r * h;
  const double bound = inscribed_deficit_bound(longest_boundary_edge(mesh), r);
  ASSERT_LT(bound, 0.05);  // the bound only means something while the faces are small against R
  const double volume = mesh_volume(mesh);
  EXPECT_LE(volume, exact * (1 + 1e-9));  // inscribed in a convex body
  EXPECT_GE(volume, exact * (1 - bound));
  EXPECT_EQ(mesh.region_names, std::vector<std::string>{"all"});

  // Nodes on a face lie on it: planes up to round-off, the curved face to the accuracy of OCC's
  // parametrisation (1e-9 of the radius is far above round-off and far below any mesh feature).
  for (const Index n : node_set(mesh, "bottom")) EXPECT_NEAR(mesh.points[n][2], base[2], 1e-12);
  for (const Index n : node_set(mesh, "top")) EXPECT_NEAR(mesh.points[n][2], base[2] + h, 1e-12);
  for (const Index n : node_set(mesh, "side")) {
    const Vec3 d = mesh.points[n] - base;
    EXPECT_NEAR(std::hypot(d[0], d[1]), r, 1e-9 * r);
  }
  // Together they are the boundary nodes.
  std::vector<char> in_sets(mesh.points.size(), 0);
  for (const char* name : {"bottom", "top", "side"})
    for (const Index n : node_set(mesh, name)) in_sets[static_cast<std::size_t>(n)] = 1;
  EXPECT_EQ(in_sets, surface_nodes(mesh));
}

TEST(GmshCylinder, IsDeterministic) {
  const json block = {{"radius", 0.015}, {"height", 0.017}, {"target_nodes", 1000}};
  EXPECT_TRUE(identical(load("cylinder", block), load("cylinder", block)));
}

TEST(GmshCylinder, RefinesAlongASegment) {
  // The paper's small sample at mesh size 2 mm, refined to 0.4 x 2 mm within 2 mm of the needle's path (the
  // axis, 15 mm down from the top). Gmsh aims at the requested size; the edges it makes spread around it.
  const double h = 0.002;
  const TetMesh mesh = load("cylinder", {{"radius", 0.015},
                                         {"height", 0.017},
                                         {"mesh_size", h},
                                         {"refine_from", {0.0, 0.0, 0.017}},
                                         {"refine_to", {0.0, 0.0, 0.002}},
                                         {"refine_distance", 0.002}});
  const auto from_axis = [](const Vec3& x) { return std::hypot(x[0], x[1]); };
  const Spacing near =
      spacing_where(mesh, [&](const Vec3& x) { return from_axis(x) < 0.0015 && x[2] > 0.003 && x[2] < 0.016; });
  const Spacing far = spacing_where(mesh, [&](const Vec3& x) { return from_axis(x) > 0.009; });
  ASSERT_GT(near.nodes, 20);
  EXPECT_NEAR(near.mean / far.mean, 0.4, 0.12);  // the ratio asked for, within Gmsh's spread
  EXPECT_NEAR(far.mean, h, 0.3 * h);
  // Half an end is an error naming the missing one.
  auto half = make<MeshSource>("cylinder", {{"radius", 0.015}, {"height", 0.017}, {"refine_from", {0.0, 0.0, 0.017}}});
  const Problem problem = input_error([&] { half->load(MeshContext{}); });
  EXPECT_EQ(problem.where, "/test/refine_to");
}

TEST(GmshCylinder, AnAbsoluteRefineSizeIsTheSameWhateverTheMeshSize) {
  // refine_size 0.8 mm along the axis at mesh sizes 2 and 3 mm: the spacing by the axis is what 0.8 mm gives (0.4
  // of what 2 mm gives far from it), the same on both, while the bulk keeps its own size.
  const auto from_axis = [](const Vec3& x) { return std::hypot(x[0], x[1]); };
  std::vector<double> near, far;
  for (const double h : {0.002, 0.003}) {
    const TetMesh mesh = load("cylinder", {{"radius", 0.015},
                                           {"height", 0.017},
                                           {"mesh_size", h},
                                           {"refine_from", {0.0, 0.0, 0.017}},
                                           {"refine_to", {0.0, 0.0, 0.002}},
                                           {"refine_size", 0.0008},
                                           {"refine_distance", 0.002}});
    const Spacing by_axis =
        spacing_where(mesh, [&](const Vec3& x) { return from_axis(x) < 0.0015 && x[2] > 0.003 && x[2] < 0.016; });
    ASSERT_GT(by_axis.nodes, 20);
    near.push_back(by_axis.mean);
    far.push_back(spacing_where(mesh, [&](const Vec3& x) { return from_axis(x) > 0.009; }).mean);
  }
  std::printf("by the axis %.3f and %.3f mm, far %.3f and %.3f mm\n", 1e3 * near[0], 1e3 * near[1], 1e3 * far[0],
              1e3 * far[1]);
  EXPECT_NEAR(near[1] / near[0], 1.0, 0.12);  // Gmsh's spread, as above
  EXPECT_NEAR(near[0] / far[0], 0.4, 0.12);
  EXPECT_NEAR(far[1] / far[0], 1.5, 0.3);
  // A ratio and a size at once is refused, naming the size.
  auto both = make<MeshSource>("cylinder", {{"radius", 0.015},
                                            {"height", 0.017},
                                            {"refine_from", {0.0, 0.0, 0.017}},
                                            {"refine_to", {0.0, 0.0, 0.002}},
                                            {"refine_ratio", 0.5},
                                            {"refine_size", 0.0008}});
  EXPECT_EQ(input_error([&] { both->load(MeshContext{}); }).where, "/test/refine_size");
  // A size with no segment to refine along refines nothing: said, not refused.
  testing::internal::CaptureStderr();
  load("cylinder", {{"radius", 0.015}, {"height", 0.017}, {"mesh_size", 0.004}, {"refine_size", 0.0008}});
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("/test/refine_size is given but refines nothing"), std::string::npos) << said;
}

// refine_along_needle takes the segment from the scene's needle (MeshContext::needle_path): the same mesh as its
// entry and tip given as refine_from and refine_to. Without a needle, or with both, it is refused, naming itself.
TEST(GmshCylinder, RefinesAlongTheNeedlesPlannedPath) {
  const json along = {{"radius", 0.015},
                      {"height", 0.017},
                      {"mesh_size", 0.003},
                      {"refine_along_needle", true},
                      {"refine_size", 0.001}};
  json given = along;
  given.erase("refine_along_needle");
  given["refine_from"] = {0.002, 0.0, 0.017};
  given["refine_to"] = {0.002, 0.0, 0.004};
  MeshContext with_needle;
  with_needle.needle_path = [] { return PlannedPath{Vec3(0.002, 0.0, 0.017), Vec3(0.002, 0.0, 0.004), ""}; };
  const TetMesh from_needle = kernel_ready(make<MeshSource>("cylinder", along)->load(with_needle));
  const TetMesh from_ends = load("cylinder", given);
  ASSERT_EQ(from_needle.node_count(), from_ends.node_count());
  EXPECT_EQ(from_needle.points, from_ends.points);
  EXPECT_GT(
      from_needle.node_count(),
      load("cylinder", {{"radius", 0.015}, {"height", 0.017}, {"mesh_size", 0.003}}).node_count());  // it did refine
  EXPECT_EQ(input_error([&] { make<MeshSource>("cylinder", along)->load(MeshContext{}); }).where,
            "/test/refine_along_needle");
  json both = given;
  both["refine_along_needle"] = true;
  EXPECT_EQ(input_error([&] { make<MeshSource>("cylinder", both)->load(with_needle); }).where,
            "/test/refine_along_needle");
}

TEST(GmshCylinder, RefinesAlongTheRims) {
  // The semi-confined sample at mesh size 3 mm, refined to 0.25 x 3 mm within 1 mm of the two rims (where the
  // bonded faces meet the side), growing back to 3 mm over the next 6 mm: near the rims the edges are about a
  // quarter of those at mid-height on the axis, and the middle of the side keeps the bulk size.
  const double h = 0.003, r = 0.015, height = 0.017;
  const TetMesh mesh = load("cylinder", {{"radius", r},
                                         {"height", height},
                                         {"mesh_size", h},
                                         {"refine_rims", true},
                                         {"refine_ratio", 0.25},
                                         {"refine_distance", 0.001},
                                         {"refine_transition", 0.006}});
  const auto to_rim = [&](const Vec3& x) {
    return std::hypot(r - std::hypot(x[0], x[1]), std::min(x[2], height - x[2]));
  };
  const Spacing near = spacing_where(mesh, [&](const Vec3& x) { return to_rim(x) < 0.0008; });
  const Spacing far = spacing_where(mesh, [&](const Vec3& x) { return to_rim(x) > 0.0075; });
  ASSERT_GT(near.nodes, 100);
  ASSERT_GT(far.nodes, 20);
  EXPECT_NEAR(near.mean / far.mean, 0.25, 0.08);  // the ratio asked for, within Gmsh's spread
  EXPECT_NEAR(far.mean, h, 0.3 * h);
  // The box has no rims: the option is not declared there, and a scene that gives it is told so.
  std::vector<Problem> problems;
  validate_parameters(catalog().load(Category::mesh, "box"), {{"size", {0.01, 0.01, 0.01}}, {"refine_rims", true}},
                      "/mesh", problems);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].where, "/mesh/refine_rims");
}

TEST(GmshCylinder, RefusesSizesCoarserThanTheRadius) {
  // A needle-thin cylinder: 1,000 nodes would need a mesh size above the radius (a circle of under 6
  // segments, on which Gmsh spends minutes). Refused before meshing, with the node count that would do.
  auto thin = make<MeshSource>("cylinder", {{"radius", 1e-4}, {"height", 0.1}, {"target_nodes", 1000}});
  const Problem few = input_error([&] { thin->load(MeshContext{}); });
  EXPECT_EQ(few.where, "/test/target_nodes");
  EXPECT_NE(few.message.find("ask for at least"), std::string::npos) << few.message;
  auto coarse = make<MeshSource>("cylinder", {{"radius", 0.01}, {"height", 0.01}, {"mesh_size", 0.02}});
  const Problem size = input_error([&] { coarse->load(MeshContext{}); });
  EXPECT_EQ(size.where, "/test/mesh_size");
  EXPECT_NE(size.message.find("at most 0.01 m"), std::string::npos) << size.message;
}

TEST(GmshLayeredCylinder, LayersAreRegionsWithTheirVolumes) {
  // The paper's large sample scaled down by 2, so that a small mesh still resolves the thin top layer.
  const double r = 0.01625;
  const std::vector<double> heights{0.009, 0.0045, 0.0035};
  const TetMesh mesh = load("layered_cylinder", {{"radius", r},
                                                 {"layer_heights", heights},
                                                 {"layer_names", {"bottom_gel", "middle_gel", "top_gel"}},
                                                 {"target_nodes", 3000}});
  EXPECT_NEAR(mesh.node_count(), 3000, 0.03 * 3000);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"bottom_gel", "middle_gel", "top_gel"}));
  const double bound = inscribed_deficit_bound(longest_boundary_edge(mesh), r);
  const char* names[3] = {"bottom_gel", "middle_gel", "top_gel"};
  for (int k = 0; k < 3; ++k) {
    const double exact = std::numbers::pi * r * r * heights[static_cast<std::size_t>(k)];
    const double volume = region_volume(mesh, names[k]);
    EXPECT_LE(volume, exact * (1 + 1e-9)) << names[k];
    EXPECT_GE(volume, exact * (1 - bound)) << names[k];
  }
  // Interfaces and faces at their heights; every interface node is shared by the tets of both layers
  // (a conformal mesh), which shows as interface nodes that are not on the outer surface.
  const double levels[4] = {0.0, 0.009, 0.0135, 0.017};
  const char* planes[4] = {"bottom", "interface1", "interface2", "top"};
  const std::vector<char> surface = surface_nodes(mesh);
  for (int k = 0; k < 4; ++k) {
    std::size_t interior = 0;
    for (const Index n : node_set(mesh, planes[k])) {
      EXPECT_NEAR(mesh.points[n][2], levels[k], 1e-12) << planes[k];
      interior += surface[static_cast<std::size_t>(n)] ? 0 : 1;
    }
    const bool is_interface = k == 1 || k == 2;
    EXPECT_EQ(interior > 0, is_interface) << planes[k] << ": " << interior << " nodes inside the body";
  }
  for (const Index n : node_set(mesh, "side")) EXPECT_NEAR(mesh.points[n].head<2>().norm(), r, 1e-9 * r);
  // No tet straddles an interface: every tet of layer k lies between its levels.
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    const auto layer = static_cast<std::size_t>(mesh.tet_region[t]);
    for (const Index n : mesh.tets[t]) {
      EXPECT_GE(mesh.points[n][2], levels[layer] - 1e-12);
      EXPECT_LE(mesh.points[n][2], levels[layer + 1] + 1e-12);
    }
  }
}

TEST(GmshLayeredCylinder, DefaultNamesAndOneLayer) {
  const TetMesh mesh =
      load("layered_cylinder", {{"radius", 0.01}, {"layer_heights", {0.01, 0.005}}, {"target_nodes", 800}});
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"layer1", "layer2"}));
  EXPECT_EQ(mesh.node_sets.count("interface1"), 1u);
  EXPECT_EQ(mesh.node_sets.count("interface2"), 0u);
  const TetMesh single = load("layered_cylinder", {{"radius", 0.01}, {"layer_heights", {0.01}}, {"target_nodes", 500}});
  EXPECT_EQ(single.region_names, std::vector<std::string>{"layer1"});
  for (const char* name : {"bottom", "top", "side"}) EXPECT_EQ(single.node_sets.count(name), 1u) << name;
}

TEST(GmshLayeredCylinder, RejectsBadLayerNames) {
  const Problem count = input_error([] {
    make<MeshSource>("layered_cylinder", {{"radius", 0.01}, {"layer_heights", {0.01, 0.005}}, {"layer_names", {"a"}}});
  });
  EXPECT_EQ(count.where, "/test/layer_names");
  EXPECT_NE(count.message.find("one name per"), std::string::npos) << count.message;
  const Problem twice = input_error([] {
    make<MeshSource>("layered_cylinder",
                     {{"radius", 0.01}, {"layer_heights", {0.01, 0.005}}, {"layer_names", {"gel", "gel"}}});
  });
  EXPECT_EQ(twice.where, "/test/layer_names/1");
  const Problem none = input_error([] {
    make<MeshSource>("layered_cylinder", {{"radius", 0.01}, {"layer_heights", json::array()}});
  });
  EXPECT_EQ(none.where, "/test/layer_heights");
}

}  // namespace
}  // namespace mtled::test
