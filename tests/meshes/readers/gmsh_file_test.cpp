// gmsh_file: MSH 2.2 and 4.1 written by hand and by Gmsh, physical groups, and every way a file can be bad.
#include <ostream>
#include <fmt/format.h>

#include "reader_test_support.hpp"

namespace mtled::test {
namespace {

// A hand-written MSH 2.2 file around `elements` (the $Elements body, count first): a unit tet and a second
// tet sharing its face, nodes 10, 20, 30, 40, 50.
std::string msh22(const std::string& elements, const std::string& names = "") {
  return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" + names +
         "$Nodes\n5\n10 0 0 0\n20 1 0 0\n30 0 1 0\n40 0 0 1\n50 1 1 1\n$EndNodes\n$Elements\n" + elements +
         "$EndElements\n";
}

TEST(GmshFile, HandWrittenMsh22AndMsh41GiveTheReferenceCube) {
  const TetMesh v2 = read_mesh("gmsh_file", {{"path", "cube_msh22.msh"}});
  const TetMesh v4 = read_mesh("gmsh_file", {{"path", "cube_msh41.msh"}});
  EXPECT_EQ(v2.tet_count(), 12);
  EXPECT_EQ(v2.node_count(), 12);
  EXPECT_EQ(canonical(v2), reference_cube());
  EXPECT_EQ(canonical(v4), reference_cube());
  // Regions by ascending physical tag (left = 1, right = 2).
  EXPECT_EQ(v2.region_names, (std::vector<std::string>{"left", "right"}));
  EXPECT_EQ(v4.region_names, (std::vector<std::string>{"left", "right"}));
  EXPECT_NE(v2.source.find("cube_msh22.msh"), std::string::npos);
}

TEST(GmshFile, GmshWrittenMsh22AndMsh41Agree) {
  // cube.geo meshed by Gmsh 4.8 three times: MSH 2.2, MSH 4.1, and MSH 4.1 with Mesh.SaveAll (points, lines
  // and triangles of every entity beside the tets).
  const TetMesh v2 = read_mesh("gmsh_file", {{"path", "cube_gmsh22.msh"}});
  const TetMesh v4 = read_mesh("gmsh_file", {{"path", "cube_gmsh41.msh"}});
  const TetMesh all = read_mesh("gmsh_file", {{"path", "cube_gmsh41_all.msh"}});
  EXPECT_GT(v2.tet_count(), 12);
  EXPECT_EQ(canonical(v2), canonical(v4));
  EXPECT_EQ(canonical(all), canonical(v4));
  EXPECT_EQ(v4.region_names, (std::vector<std::string>{"left", "right"}));
  ASSERT_EQ(v4.node_sets.count("bottom"), 1u);
  ASSERT_EQ(v4.node_sets.count("top"), 1u);
  for (Index n : v4.node_sets.at("bottom")) EXPECT_EQ(v4.points[n][2], 0.0);
  for (Index n : v4.node_sets.at("top")) EXPECT_EQ(v4.points[n][2], 1.0);
  // Each box is 0.5 m^3; the sum of tet volumes is exact up to rounding (~1e-16 per tet).
  TetMesh mesh = v4;
  remove_unused_nodes(mesh);
  check_mesh(mesh);
  double left = 0.0;
  for (Index t = 0; t < mesh.tet_count(); ++t)
    if (mesh.tet_region[t] == 0) left += tet_volume(mesh, t);
  EXPECT_NEAR(total_volume(mesh), 1.0, 1e-12);
  EXPECT_NEAR(left, 0.5, 1e-12);
}

TEST(GmshFile, TetsOutsidePhysicalVolumesFormRegionUnassigned) {
  const auto dir = folder_with_file("gmsh_file/unassigned", "m.msh",
                                    msh22("2\n1 4 2 7 1 10 20 30 40\n2 4 2 0 2 20 30 40 50\n",
                                          "$PhysicalNames\n1\n3 7 \"liver tissue\"\n$EndPhysicalNames\n"));
  const TetMesh mesh = read_mesh("gmsh_file", {{"path", "m.msh"}}, dir);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"liver tissue", "unassigned"}));
  EXPECT_EQ(mesh.tet_region, (std::vector<Index>{0, 1}));
}

TEST(GmshFile, WithoutPhysicalGroupsTheRegionIsAllAndUnnamedGroupsAreNumbers) {
  auto dir = folder_with_file("gmsh_file/none", "m.msh", msh22("2\n1 4 0 10 20 30 40\n2 4 0 20 30 40 50\n"));
  TetMesh mesh = read_mesh("gmsh_file", {{"path", "m.msh"}}, dir);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"all"}));
  EXPECT_EQ(mesh.tet_region, (std::vector<Index>{0, 0}));
  EXPECT_TRUE(mesh.node_sets.empty());

  // Physical groups 5 (volume) and 9 (a point, element type 15) without $PhysicalNames.
  dir = folder_with_file("gmsh_file/numbers", "m.msh",
                         msh22("3\n1 15 2 9 1 50\n2 4 2 5 1 10 20 30 40\n3 4 2 5 1 20 30 40 50\n"));
  mesh = read_mesh("gmsh_file", {{"path", "m.msh"}}, dir);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"5"}));
  ASSERT_EQ(mesh.node_sets.count("9"), 1u);
  EXPECT_EQ(mesh.node_sets.at("9"), (std::vector<Index>{4}));  // node 50 is the fifth
}

TEST(GmshFile, ScaleMultipliesCoordinates) {
  const TetMesh metres = read_mesh("gmsh_file", {{"path", "cube_msh41.msh"}});
  const TetMesh scaled = read_mesh("gmsh_file", {{"path", "cube_msh41.msh"}, {"scale", 0.001}});
  ASSERT_EQ(scaled.points.size(), metres.points.size());
  // One multiplication: exact to the last bit of the product.
  for (std::size_t i = 0; i < metres.points.size(); ++i)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(scaled.points[i][d], metres.points[i][d] * 0.001);
}

TEST(GmshFile, AbsolutePathsIgnoreTheSceneFolder) {
  const TetMesh mesh = read_mesh("gmsh_file", {{"path", (fixtures() / "cube_msh22.msh").string()}},
                                 std::filesystem::path("/nonexistent"));
  EXPECT_EQ(mesh.tet_count(), 12);
}

// --- errors ---

struct BadMsh {
  std::string name;
  std::string text;
  int line;             // expected line in "where"
  std::string message;  // expected part of the message
  // Short value in test names (ctest would otherwise show the object's bytes).
  friend void PrintTo(const BadMsh& c, std::ostream* os) { *os << c.name; }
};

class GmshFileErrors : public ::testing::TestWithParam<BadMsh> {};

TEST_P(GmshFileErrors, NameTheLineAndSayWhatToDo) {
  const BadMsh& bad = GetParam();
  const auto dir = folder_with_file("gmsh_file/error_" + bad.name, "bad.msh", bad.text);
  const InputError error = read_error("gmsh_file", {{"path", "bad.msh"}}, dir);
  EXPECT_EQ(where_of(error), fmt::format("{}:{}", (dir / "bad.msh").string(), bad.line)) << message_of(error);
  EXPECT_NE(message_of(error).find(bad.message), std::string::npos) << message_of(error);
}

const std::string kMshNodes = "$Nodes\n5\n10 0 0 0\n20 1 0 0\n30 0 1 0\n40 0 0 1\n50 1 1 1\n$EndNodes\n";
const std::string kHeader = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

INSTANTIATE_TEST_SUITE_P(
    Cases, GmshFileErrors,
    ::testing::Values(
        BadMsh{"version40", "$MeshFormat\n4 0 8\n$EndMeshFormat\n", 2, "-format msh41"},
        BadMsh{"version3", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", 2, "mtled reads ASCII MSH 2.2 and 4.1"},
        BadMsh{"msh1", "$NOD\n1\n1 0 0 0\n$ENDNOD\n", 1, "MSH 1"},
        BadMsh{"not_msh", "solid cube\nfacet normal 0 0 1\n", 1, "expected $MeshFormat"},
        // Cut in the middle of $Nodes: the file ends on line 7 after 2 of 5 nodes.
        BadMsh{"truncated_nodes", kHeader + "$Nodes\n5\n10 0 0 0\n20 1 0 0\n", 7,
               "ends inside the $Nodes section that starts on line 4 after 2 of 5 nodes"},
        BadMsh{"truncated_elements", kHeader + kMshNodes + "$Elements\n2\n1 4 0 10 20 30 40\n", 14,
               "the file ends inside the $Elements section"},
        BadMsh{"missing_end", kHeader + kMshNodes + "$Elements\n1\n1 4 0 10 20 30 40\n", 14,
               "ends before $EndElements"},
        BadMsh{"count_too_small",
               kHeader + kMshNodes + "$Elements\n1\n1 4 0 10 20 30 40\n2 4 0 20 30 40 50\n$EndElements\n", 15,
               "expected $EndElements"},
        BadMsh{"unknown_node", kHeader + kMshNodes + "$Elements\n1\n1 4 0 10 20 30 99\n$EndElements\n", 14,
               "refers to node 99, which $Nodes does not define"},
        BadMsh{"duplicate_node", kHeader + "$Nodes\n2\n10 0 0 0\n10 1 0 0\n$EndNodes\n", 7,
               "node 10 is defined twice (first on line 6)"},
        BadMsh{"not_a_number", kHeader + "$Nodes\n1\n10 0 zero 0\n$EndNodes\n", 6,
               "expected the y coordinate (a finite number), found \"zero\""},
        BadMsh{"second_order",
               kHeader + kMshNodes + "$Elements\n1\n1 11 0 10 20 30 40 10 20 30 40 50 50\n$EndElements\n", 14,
               "gmsh -3 -order 1"},
        BadMsh{"hexahedron", kHeader + kMshNodes + "$Elements\n1\n1 5 0 10 20 30 40 50 10 20 30\n$EndElements\n", 14,
               "tet-only mesh"},
        BadMsh{"wrong_node_count", kHeader + kMshNodes + "$Elements\n1\n1 4 0 10 20 30\n$EndElements\n", 14,
               "should have 7 fields, found 6"},
        BadMsh{"duplicate_tet",
               kHeader + kMshNodes + "$Elements\n2\n1 4 2 1 1 10 20 30 40\n2 4 2 2 1 40 30 20 10\n$EndElements\n", 15,
               "repeats the tet of line 14"},
        BadMsh{"two_volume_groups",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 2 1 2 0\n$EndEntities\n"
               "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
               "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n",
               22, "belongs to 2 physical groups"},
        BadMsh{"v41_truncated_block",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n", 12,
               "the file ends inside the $Nodes section that starts on line 4 after 2 of 4 nodes"},
        // Counts near the largest integer overflowed the reader's arithmetic (undefined behaviour, which UBSan
        // reports): they must be refused like any other wrong count.
        BadMsh{"huge_tag_count",
               kHeader + kMshNodes + "$Elements\n1\n1 4 9223372036854775807 10 20 30 40\n$EndElements\n", 14,
               "with 9223372036854775807 tags"},
        BadMsh{"huge_node_block",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n2 2 1 2\n0 1 0 1\n1\n0 0 0\n0 2 0 9223372036854775807\n"
               "$EndNodes\n",
               9, "the node blocks hold more nodes than the $Nodes header announces (2)"},
        BadMsh{"huge_entity_counts",
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n9223372036854775807 9223372036854775807 0 0\n"
               "$EndEntities\n",
               6, "the $Entities section that starts on line 4 ends after 0 of"}),
    [](const auto& test_case) { return test_case.param.name; });

TEST(GmshFileErrorsWithoutLine, NoTetsEmptyAndMissingFiles) {
  auto dir = folder_with_file("gmsh_file/no_tets", "m.msh",
                              kHeader + kMshNodes + "$Elements\n1\n1 2 0 10 20 30\n$EndElements\n");
  InputError error = read_error("gmsh_file", {{"path", "m.msh"}}, dir);
  EXPECT_EQ(where_of(error), (dir / "m.msh").string());
  EXPECT_NE(message_of(error).find("no 4-node tetrahedra"), std::string::npos) << message_of(error);

  dir = folder_with_file("gmsh_file/empty", "m.msh", "\n  \n");
  error = read_error("gmsh_file", {{"path", "m.msh"}}, dir);
  EXPECT_EQ(where_of(error), (dir / "m.msh").string());
  EXPECT_NE(message_of(error).find("empty"), std::string::npos) << message_of(error);

  // A missing file is a bad scene value: "where" is the parameter, the message suggests the close name.
  error = read_error("gmsh_file", {{"path", "cube_msh2.msh"}});
  EXPECT_EQ(where_of(error), "/test/path");
  EXPECT_NE(message_of(error).find("does not exist"), std::string::npos) << message_of(error);
  EXPECT_NE(message_of(error).find("cube_msh22.msh"), std::string::npos) << message_of(error);

  // A path through a sibling folder is named normalised, as a user would write it (not "scenes/../meshes").
  error = read_error("gmsh_file", {{"path", "../meshes/absent.msh"}}, fixtures() / "scenes");
  EXPECT_NE(message_of(error).find((fixtures() / "meshes" / "absent.msh").lexically_normal().string()),
            std::string::npos)
      << message_of(error);
  EXPECT_EQ(message_of(error).find("/../"), std::string::npos) << message_of(error);
}

}  // namespace
}  // namespace mtled::test
