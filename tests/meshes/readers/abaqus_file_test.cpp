// abaqus_file: flat and part/assembly input files, sets, *INCLUDE, and bad files.
#include <ostream>
#include <fmt/format.h>

#include "reader_test_support.hpp"

namespace mtled::test {
namespace {

TEST(AbaqusFile, CubeGivesTheReferenceCube) {
  // cube.inp: two *NODE blocks, ids not 1..n, S3 surface elements (skipped), keywords in mixed case, an
  // *ELEMENT keyword line continued on the next line, an element whose nodes continue on the next line, a
  // region set named at *ELEMENT ("right") and extended by a later *ELSET ("RIGHT", GENERATE), *NSET with
  // and without GENERATE, and material and step keywords that are skipped.
  const TetMesh mesh = read_mesh("abaqus_file", {{"path", "cube.inp"}});
  EXPECT_EQ(mesh.tet_count(), 12);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"left", "right"}));
  EXPECT_EQ(canonical(mesh), reference_cube());
}

TEST(AbaqusFile, GmshInpExportWithRegionsNamed) {
  // Gmsh writes *ELEMENT blocks named after entities (Volume1, ...) and the physical groups as later
  // *ELSETs; its CPS3 surface elements are skipped.
  const TetMesh by_entity = read_mesh("abaqus_file", {{"path", "cube_gmsh.inp"}});
  EXPECT_EQ(by_entity.region_names, (std::vector<std::string>{"Volume1", "Volume2"}));
  const TetMesh by_group = read_mesh("abaqus_file", {{"path", "cube_gmsh.inp"}, {"regions", {"left", "right"}}});
  // The .inp export prints coordinates with 16 significant digits where the .msh has 17 (0.5 for
  // 0.4999999999999999): compare on a 1e-9 m grid, far finer than the 0.5 m mesh and far coarser than 1e-16.
  constexpr double kGrid = 1e-9;
  CanonicalMesh expected = canonical(read_mesh("gmsh_file", {{"path", "cube_gmsh41.msh"}}), {}, kGrid);
  expected.node_sets.clear();  // Gmsh's .inp export has no *NSET unless Mesh.SaveGroupsOfNodes is set
  EXPECT_EQ(canonical(by_group, {}, kGrid), expected);

  const InputError error = read_error("abaqus_file", {{"path", "cube_gmsh.inp"}, {"regions", {"left", "rihgt"}}});
  EXPECT_EQ(where_of(error), "/test/regions");
  EXPECT_NE(message_of(error).find("did you mean \"right\""), std::string::npos) << message_of(error);
}

TEST(AbaqusFile, SinglePartInstanceAsAbaqusCaeWritesIt) {
  const auto dir = folder_with_file("abaqus_file/part", "part.inp", R"(*Heading
** Job name: cube Model name: Model-1
*Preprint, echo=NO, model=NO, history=NO, contact=NO
*Part, name=Cube
*Node
      1,           0.,           0.,           0.
      2,           1.,           0.,           0.
      3,           0.,           1.,           0.
      4,           0.,           0.,           1.
      5,           1.,           1.,           1.
*Element, type=C3D4
1, 1, 2, 3, 4
2, 2, 3, 4, 5
*Nset, nset=Set-Base, generate
 1,  3,  1
*Elset, elset=Set-Tissue
 1,
*Elset, elset=Set-Tumour
 2,
** Section: Tissue
*Solid Section, elset=Set-Tissue, material=Tissue
,
*Solid Section, elset=SET-TUMOUR, material=Tumour
,
*End Part
*Assembly, name=Assembly
*Instance, name=Cube-1, part=Cube
 0.5, 0., 0.
*End Instance
*Nset, nset=Tip, instance=Cube-1
 5,
*Nset, nset=Both, instance=Cube-1
 Tip, Cube-1.Set-Base
*Node
 1, 0., 0., 5.
*Nset, nset=RefPt
 1,
*End Assembly
*Material, name=Tissue
*Hyperelastic, neo hooke
 1000., 0.
)");
  const TetMesh mesh = read_mesh("abaqus_file", {{"path", "part.inp"}}, dir);
  // Regions from *SOLID SECTION; the instance's translation moves the nodes; the reference point of the
  // assembly and its set are not part of the mesh.
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"Set-Tissue", "Set-Tumour"}));
  EXPECT_EQ(mesh.tet_region, (std::vector<Index>{0, 1}));
  ASSERT_EQ(mesh.points.size(), 5u);
  EXPECT_EQ(mesh.points[0], Vec3(0.5, 0.0, 0.0));
  EXPECT_EQ(mesh.points[4], Vec3(1.5, 1.0, 1.0));
  EXPECT_EQ(mesh.node_sets.at("Set-Base"), (std::vector<Index>{0, 1, 2}));
  EXPECT_EQ(mesh.node_sets.at("Tip"), (std::vector<Index>{4}));
  EXPECT_EQ(mesh.node_sets.at("Both"), (std::vector<Index>{0, 1, 2, 4}));
  EXPECT_EQ(mesh.node_sets.count("RefPt"), 0u);
}

TEST(AbaqusFile, IncludeSetsFromElementsAndUnassignedTets) {
  const auto dir = folder_with_file("abaqus_file/include", "main.inp", R"(*INCLUDE, INPUT=nodes.inp
*ELEMENT, TYPE=C3D4, ELSET=liver
1, 10, 20, 30, 40
*ELEMENT, TYPE=C3D4H
2, 20, 30, 40, 50
*NSET, NSET=liver_nodes, ELSET=liver
)");
  write_text(dir / "nodes.inp",
             "** nodes\n*NODE, NSET=every\n10, 0, 0, 0\n20, 1, 0, 0\n30, 0, 1, 0\n40, 0, 0, 1\n"
             "50, 1, 1, 1\n");
  const TetMesh mesh = read_mesh("abaqus_file", {{"path", "main.inp"}}, dir);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"liver", "unassigned"}));
  EXPECT_EQ(mesh.tet_region, (std::vector<Index>{0, 1}));
  EXPECT_EQ(mesh.node_sets.at("every"), (std::vector<Index>{0, 1, 2, 3, 4}));
  EXPECT_EQ(mesh.node_sets.at("liver_nodes"), (std::vector<Index>{0, 1, 2, 3}));

  // An error in the included file names that file and its line.
  write_text(dir / "nodes.inp", "*NODE\n10, 0, 0, 0\n20, 1, 0, zero\n");
  const InputError error = read_error("abaqus_file", {{"path", "main.inp"}}, dir);
  EXPECT_EQ(where_of(error), (dir / "nodes.inp").string() + ":3");
}

// A set named in itself was copied into itself, doubling with each mention: 40 mentions wanted 2^40 members.
// GENERATE ids near the ends of the integer range overflowed the arithmetic.
TEST(AbaqusFile, SetNamedInItselfAndExtremeGenerateRanges) {
  std::string again;
  for (int i = 0; i < 40; ++i) again += "a, ";
  const auto dir =
      folder_with_file("abaqus_file/self_set", "m.inp",
                       "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*ELEMENT,TYPE=C3D4\n1,1,2,3,4\n"
                       "*NSET, NSET=a\n1\n" +
                           again + "a\n*NSET, NSET=b, GENERATE\n2, 9223372036854775807, 9223372036854775807\n");
  const TetMesh mesh = read_mesh("abaqus_file", {{"path", "m.inp"}}, dir);
  EXPECT_EQ(mesh.node_sets.at("a"), (std::vector<Index>{0}));
  EXPECT_EQ(mesh.node_sets.at("b"), (std::vector<Index>{1}));
}

TEST(AbaqusFile, WithoutElementSetsTheRegionIsAll) {
  const auto dir = folder_with_file("abaqus_file/no_sets", "m.inp",
                                    "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*ELEMENT,TYPE=C3D4\n1,1,2,3,4\n");
  const TetMesh mesh = read_mesh("abaqus_file", {{"path", "m.inp"}}, dir);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"all"}));
  EXPECT_EQ(mesh.tet_region, (std::vector<Index>{0}));
}

TEST(AbaqusFile, ScaleMultipliesCoordinates) {
  const TetMesh metres = read_mesh("abaqus_file", {{"path", "cube.inp"}});
  const TetMesh scaled = read_mesh("abaqus_file", {{"path", "cube.inp"}, {"scale", 0.001}});
  ASSERT_EQ(scaled.points.size(), metres.points.size());
  for (std::size_t i = 0; i < metres.points.size(); ++i)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(scaled.points[i][d], metres.points[i][d] * 0.001);
}

// --- errors ---

struct BadInp {
  std::string name;
  std::string text;
  int line;             // expected line in "where"
  std::string message;  // expected part of the message
  // Short value in test names (ctest would otherwise show the object's bytes).
  friend void PrintTo(const BadInp& c, std::ostream* os) { *os << c.name; }
};

class AbaqusFileErrors : public ::testing::TestWithParam<BadInp> {};

TEST_P(AbaqusFileErrors, NameTheLineAndSayWhatToDo) {
  const BadInp& bad = GetParam();
  const auto dir = folder_with_file("abaqus_file/error_" + bad.name, "bad.inp", bad.text);
  const InputError error = read_error("abaqus_file", {{"path", "bad.inp"}}, dir);
  EXPECT_EQ(where_of(error), fmt::format("{}:{}", (dir / "bad.inp").string(), bad.line)) << message_of(error);
  EXPECT_NE(message_of(error).find(bad.message), std::string::npos) << message_of(error);
}

const std::string kInpNodes = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n5, 1, 1, 1\n";  // lines 1-6

INSTANTIATE_TEST_SUITE_P(
    Cases, AbaqusFileErrors,
    ::testing::Values(
        BadInp{"quadratic_tet", kInpNodes + "*ELEMENT, TYPE=C3D10, ELSET=a\n1, 1, 2, 3, 4, 5, 1, 2, 3, 4, 5\n", 7,
               "mesh with linear tets"},
        BadInp{"hexahedron", kInpNodes + "** comment\n*Element, type=C3D8R\n", 8, "4-node tets (C3D4)"},
        BadInp{"unknown_type", kInpNodes + "*ELEMENT, TYPE=XYZ4\n", 7, "element type XYZ4 is not supported"},
        BadInp{"no_type", kInpNodes + "*ELEMENT, ELSET=a\n", 7, "*ELEMENT needs TYPE="},
        BadInp{"duplicate_node", "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n1, 0, 1, 0\n", 4,
               "node 1 is defined twice (first on line 2)"},
        BadInp{"unknown_node", kInpNodes + "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 9\n", 8,
               "refers to node 9, which no *NODE defines"},
        BadInp{"duplicate_element", kInpNodes + "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n1, 2, 3, 4, 5\n", 9,
               "element 1 is defined twice"},
        BadInp{"not_a_number", "*NODE\n1, 0, 0, 0\n2, 1, 0,, 0\n", 3,
               "expected the z coordinate (a finite number), found \"\""},
        BadInp{"short_node_line", "*NODE\n1, 0, 0, 0\n2, 1, 0\n", 3, "a *NODE line needs \"id, x, y, z\""},
        // Cut between two lines of *NODE: no elements follow.
        BadInp{"truncated_nodes", "*HEADING\ncut\n*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n", 5,
               "the file ends in the *NODE block that starts on line 3: is it truncated?"},
        BadInp{"tet_fields", kInpNodes + "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3\n", 8,
               "needs \"id, n1, n2, n3, n4\", found 4 fields"},
        BadInp{"two_instances",
               "*PART, NAME=P\n*END PART\n*ASSEMBLY, NAME=A\n*INSTANCE, NAME=P-1, PART=P\n*END INSTANCE\n"
               "*INSTANCE, NAME=P-2, PART=P\n",
               6, "mtled reads a single part instance"},
        BadInp{"two_parts", "*PART, NAME=P\n*END PART\n*PART, NAME=Q\n", 3, "mtled reads one part"},
        BadInp{"rotation",
               "*PART, NAME=P\n*END PART\n*ASSEMBLY, NAME=A\n*INSTANCE, NAME=P-1, PART=P\n0, 0, 0\n"
               "0, 0, 0, 0, 0, 1, 90\n",
               6, "rotation is not supported"},
        BadInp{"unknown_set", kInpNodes + "*NSET, NSET=a\n1, base\n", 8, "\"base\" is neither an id nor a node set"},
        BadInp{"bad_generate", kInpNodes + "*NSET, NSET=a, GENERATE\n5, 1, 1\n", 8, "is not a range"},
        BadInp{"set_unknown_element", kInpNodes + "*ELEMENT, TYPE=C3D4, ELSET=a\n1, 1, 2, 3, 4\n*ELSET, ELSET=a\n7\n",
               10, "lists element 7, which no *ELEMENT defines"},
        BadInp{"overlapping_regions",
               kInpNodes + "*ELEMENT, TYPE=C3D4, ELSET=a\n1, 1, 2, 3, 4\n*ELEMENT, TYPE=C3D4, ELSET=b\n2, 2, 3, 4, 5\n"
                           "*ELSET, ELSET=b\n1\n",
               12, "element 1 is in element sets \"a\" and \"b\""},
        BadInp{"section_without_set", kInpNodes + "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*SOLID SECTION, ELSET=tissue\n",
               9, "names element set \"tissue\", which the file does not define"},
        BadInp{"system", "*SYSTEM\n0, 0, 0\n", 1, "*SYSTEM"},
        BadInp{"missing_include", "*INCLUDE, INPUT=absent.inp\n", 1, "does not exist"},
        // last - first overflowed for a range over the whole integer range, which passed the size check and
        // allocated until std::bad_alloc.
        BadInp{"generate_whole_integer_range",
               kInpNodes + "*NSET, NSET=a, GENERATE\n-9223372036854775808, 9223372036854775807, 1\n", 8,
               "is not a range"},
        // Found by tests/fuzz: the keyword line's continuation went on past the end of the file, closing it, so
        // the file included itself forever instead of ever getting 16 deep.
        BadInp{"include_itself_continued", "*INCLUDE, INPUT=bad.inp,\n", 1, "*INCLUDE nested more than 16 deep"}),
    [](const auto& test_case) { return test_case.param.name; });

}  // namespace
}  // namespace mtled::test
