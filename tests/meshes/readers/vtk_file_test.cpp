// vtk_file: legacy .vtk and XML .vtu in every encoding, region and node-set arrays, mtled's own result.vtu,
// and bad files.
#include <ostream>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mtled/io/output.hpp"
#include "reader_test_support.hpp"

namespace mtled::test {
namespace {

// The fixtures number the regions by Gmsh's physical tags: left = 1, right = 2.
const std::map<std::string, std::string> kCubeRegions = {{"1", "left"}, {"2", "right"}};
const json kNodeSets = {"bottom", "top"};

class VtkFixtures : public ::testing::TestWithParam<std::string> {};

TEST_P(VtkFixtures, GiveTheReferenceCube) {
  // Triangles (VTK type 5) stand beside the tets in every fixture and must be skipped.
  const TetMesh mesh = read_mesh("vtk_file", {{"path", GetParam()}, {"node_set_arrays", kNodeSets}});
  EXPECT_EQ(mesh.tet_count(), 12);
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"1", "2"}));
  EXPECT_EQ(canonical(mesh, kCubeRegions), reference_cube());
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, VtkFixtures,
                         ::testing::Values("cube.vtk", "cube_v51.vtk", "cube.vtu", "cube_binary.vtu",
                                           "cube_appended.vtu", "cube_raw.vtu", "cube_bigendian.vtu"),
                         [](const auto& test_case) {
                           std::string name = test_case.param;
                           for (char& c : name)
                             if (c == '.') c = '_';
                           return name;
                         });

// VTK's own XML writer puts <InformationKey> elements (with <Value>s holding numbers) inside a DataArray,
// before its values, when the array carries information such as its L2-norm range: they are not values.
TEST(VtkFile, InformationKeysInsideADataArrayAreNotValues) {
  for (const std::string fixture : {"cube.vtu", "cube_binary.vtu"}) {
    SCOPED_TRACE(fixture);
    std::ifstream in(fixtures() / fixture);
    std::stringstream text;
    text << in.rdbuf();
    std::string vtu = text.str();
    const std::size_t points = vtu.find("<Points>");
    ASSERT_NE(points, std::string::npos);
    const std::size_t tag_end = vtu.find('>', vtu.find("<DataArray", points)) + 1;
    vtu.insert(tag_end,
               "\n<InformationKey name=\"L2_NORM_RANGE\" location=\"vtkDataArray\" length=\"2\">\n"
               "<Value index=\"0\">\n0\n</Value>\n<Value index=\"1\">\n1.7320508076\n</Value>\n</InformationKey>\n"
               "<InformationKey name=\"COMPONENT_NAME\" location=\"vtkAbstractArray\"/>\n");
    const auto folder = std::filesystem::temp_directory_path() / "mtled_vtk_information_key";
    std::filesystem::create_directories(folder);
    std::ofstream(folder / fixture) << vtu;
    const TetMesh mesh = read_mesh("vtk_file", {{"path", fixture}, {"node_set_arrays", kNodeSets}}, folder);
    EXPECT_EQ(canonical(mesh, kCubeRegions), reference_cube());
  }
}

TEST(VtkFile, RegionArrayChoices) {
  // "none": one region whatever the file holds; an explicit name; without node_set_arrays no node sets.
  TetMesh mesh = read_mesh("vtk_file", {{"path", "cube.vtu"}, {"region_array", "none"}});
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"all"}));
  EXPECT_TRUE(mesh.node_sets.empty());
  mesh = read_mesh("vtk_file", {{"path", "cube.vtk"}, {"region_array", "region"}});
  EXPECT_EQ(mesh.region_names, (std::vector<std::string>{"1", "2"}));

  // A name the file does not have: the error is at the parameter and lists the arrays.
  InputError error = read_error("vtk_file", {{"path", "cube.vtu"}, {"region_array", "regoin"}});
  EXPECT_EQ(where_of(error), "/test/region_array");
  EXPECT_NE(message_of(error).find("did you mean \"region\""), std::string::npos) << message_of(error);
  error = read_error("vtk_file", {{"path", "cube.vtu"}, {"node_set_arrays", {"bottom", "side"}}});
  EXPECT_EQ(where_of(error), "/test/node_set_arrays");
  EXPECT_NE(message_of(error).find("no point array \"side\""), std::string::npos) << message_of(error);
  EXPECT_NE(message_of(error).find("bottom, top"), std::string::npos) << message_of(error);
}

TEST(VtkFile, GmshVtkExportUsesCellEntityIds) {
  // Gmsh's legacy VTK export of cube.geo numbers cells by their elementary entity (volumes 1 and 2), and
  // writes the boundary triangles too; its tets are those of the .msh.
  const TetMesh vtk = read_mesh("vtk_file", {{"path", "cube_gmsh.vtk"}});
  const TetMesh msh = read_mesh("gmsh_file", {{"path", "cube_gmsh41.msh"}});
  CanonicalMesh expected = canonical(msh);
  expected.node_sets.clear();
  EXPECT_EQ(canonical(vtk, {{"1", "left"}, {"2", "right"}}), expected);
}

TEST(VtkFile, ScaleMultipliesCoordinates) {
  const TetMesh metres = read_mesh("vtk_file", {{"path", "cube_raw.vtu"}});
  const TetMesh scaled = read_mesh("vtk_file", {{"path", "cube_raw.vtu"}, {"scale", 0.001}});
  ASSERT_EQ(scaled.points.size(), metres.points.size());
  for (std::size_t i = 0; i < metres.points.size(); ++i)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(scaled.points[i][d], metres.points[i][d] * 0.001);
}

void expect_round_trip(const TetMesh& original, const std::string& test, const VtuStyle& style);

// mtled's result.vtu (core write_vtu) read back as a mesh, in both formats and both length units: same points
// (binary doubles, or 17 digits: exact in metres; in millimetres back in metres to the rounding of x 1000 and
// x 0.001), same tets in the same order, regions named by their index.
void expect_round_trip(const TetMesh& original, const std::string& test) {
  for (const VtuFormat format : {VtuFormat::binary, VtuFormat::ascii})
    for (const LengthUnit unit : {LengthUnit::metre, LengthUnit::millimetre}) {
      SCOPED_TRACE(fmt::format("{}, {}", format == VtuFormat::binary ? "binary" : "ascii",
                               unit == LengthUnit::metre ? "m" : "mm"));
      expect_round_trip(original, test, {format, unit});
    }
}

void expect_round_trip(const TetMesh& original, const std::string& test, const VtuStyle& style) {
  std::vector<double> displacement(3 * original.points.size(), 1e-3);
  std::vector<CellField> fields{{"stress", 6, std::vector<double>(6 * original.tets.size(), 1.0)}};
  const auto dir = scratch_dir("vtk_file/" + test);
  {
    std::ofstream out(dir / "result.vtu", std::ios::binary);
    write_vtu(out, original, displacement, fields, style);
  }
  const TetMesh read = read_mesh("vtk_file", {{"path", "result.vtu"}}, dir);
  ASSERT_EQ(read.points.size(), original.points.size());
  const double rounding = style.length_unit == LengthUnit::metre ? 0.0 : 4e-16;
  for (std::size_t i = 0; i < read.points.size(); ++i)
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(read.points[i][d], original.points[i][d], rounding * std::abs(original.points[i][d]))
          << "point " << i;
  ASSERT_EQ(read.tets, original.tets);
  ASSERT_EQ(read.tet_region.size(), original.tet_region.size());
  for (std::size_t t = 0; t < read.tets.size(); ++t)
    EXPECT_EQ(read.region_names[static_cast<std::size_t>(read.tet_region[t])], std::to_string(original.tet_region[t]));
}

TetMesh two_region_box(int n, double jitter) {
  TetMesh mesh = box_mesh(Vec3(0.03, 0.02, 0.017), n, n, n, jitter, 7);
  mesh.region_names = {"tissue", "tumour"};
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    Vec3 centre = Vec3::Zero();
    for (Index v : mesh.tets[t]) centre += mesh.points[v] / 4.0;
    mesh.tet_region[t] = centre[0] > 0.015 ? 1 : 0;
  }
  return mesh;
}

TEST(VtkFile, ReadsMtledsOwnResultVtu) { expect_round_trip(two_region_box(3, 0.2), "round_trip"); }

TEST(VtkFile, ReadsALargeResultVtuQuickly) {
  // 20^3 cubes x 6 = 48,000 tets, about the paper's coarse brain mesh (42,059 tets).
  const TetMesh mesh = two_region_box(20, 0.2);
  const auto start = std::chrono::steady_clock::now();
  expect_round_trip(mesh, "round_trip_large");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  RecordProperty("seconds", std::to_string(seconds));
  EXPECT_LT(seconds, 10.0);  // writing and reading ~5 MB of text: well under a second in Release
}

// --- errors ---

struct BadVtk {
  std::string name;
  std::string file;  // file name (the extension picks the format)
  std::string text;
  int line;             // expected line in "where"; 0: the file without a line
  std::string message;  // expected part of the message
  // Short value in test names (ctest would otherwise show the object's bytes).
  friend void PrintTo(const BadVtk& c, std::ostream* os) { *os << c.name; }
};

class VtkFileErrors : public ::testing::TestWithParam<BadVtk> {};

TEST_P(VtkFileErrors, NameTheLineAndSayWhatToDo) {
  const BadVtk& bad = GetParam();
  const auto dir = folder_with_file("vtk_file/error_" + bad.name, bad.file, bad.text);
  const InputError error = read_error("vtk_file", {{"path", bad.file}}, dir);
  const std::string file = (dir / bad.file).string();
  EXPECT_EQ(where_of(error), bad.line > 0 ? fmt::format("{}:{}", file, bad.line) : file) << message_of(error);
  EXPECT_NE(message_of(error).find(bad.message), std::string::npos) << message_of(error);
}

const std::string kLegacyHead = "# vtk DataFile Version 2.0\ntest\nASCII\nDATASET UNSTRUCTURED_GRID\n";
const std::string kPoints = "POINTS 5 float\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n";  // lines 5-10

std::string vtu(const std::string& cells, const std::string& types, const std::string& attributes = "",
                const std::string& format = "ascii") {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\"" + attributes +
         ">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n<Points>\n"
         "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1</DataArray>\n"
         "</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"" +
         format + "\">" + cells +
         "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray>\n"
         "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" +
         types + "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

INSTANTIATE_TEST_SUITE_P(
    Cases, VtkFileErrors,
    ::testing::Values(
        // Binary legacy files: values that end early, and a type that is not a number.
        BadVtk{"binary_truncated_points", "m.vtk",
               "# vtk DataFile Version 3.0\ntest\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 float\n" +
                   std::string(12, '\0'),
               6, "the file ends while reading POINTS"},
        BadVtk{"binary_string_points", "m.vtk",
               "# vtk DataFile Version 3.0\ntest\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 string\nabc\n", 5,
               "binary values of type \"string\""},
        BadVtk{"not_vtk", "m.vtk", "hello\n", 1, "starts with \"# vtk DataFile Version"},
        BadVtk{"polydata", "m.vtk", "# vtk DataFile Version 2.0\nt\nASCII\nDATASET POLYDATA\n", 4, "UNSTRUCTURED_GRID"},
        // Cut in the middle of POINTS: the last line read is 7, in point 2 of 5.
        BadVtk{"truncated_points", "m.vtk", kLegacyHead + "POINTS 5 float\n0 0 0\n1 0", 7,
               "the file ends while reading POINTS (point 1 of 5)"},
        BadVtk{"not_a_number", "m.vtk", kLegacyHead + "POINTS 1 float\n0 x 0\n", 6,
               "expected a point coordinate (a finite number), found \"x\""},
        BadVtk{"point_out_of_range", "m.vtk", kLegacyHead + kPoints + "CELLS 1 5\n4 0 1 2 7\nCELL_TYPES 1\n10\n", 12,
               "refers to point 7, but there are only 5 points"},
        BadVtk{"hexahedron", "m.vtk", kLegacyHead + kPoints + "CELLS 1 9\n8 0 1 2 3 4 0 1 2\nCELL_TYPES 1\n12\n", 12,
               "4-node tetrahedra"},
        BadVtk{"quadratic_tet", "m.vtk",
               kLegacyHead + kPoints + "CELLS 1 11\n10 0 1 2 3 4 0 1 2 3 4\nCELL_TYPES 1\n24\n", 12,
               "10-node quadratic"},
        BadVtk{"type_count", "m.vtk", kLegacyHead + kPoints + "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10\n10\n", 13,
               "CELL_TYPES announces 2 cells but CELLS has 1"},
        BadVtk{"cells_size", "m.vtk", kLegacyHead + kPoints + "CELLS 1 6\n4 0 1 2 3\nCELL_TYPES 1\n10\n", 11,
               "CELLS announces 6 integers but its 1 cells hold 5"},
        BadVtk{"no_tets", "m.vtk", kLegacyHead + kPoints + "CELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n", 0, "no tetrahedra"},
        BadVtk{"lz4_compressed", "m.vtu", vtu("AAAA", "10", " compressor=\"vtkLZ4DataCompressor\"", "binary"), 2,
               "SetCompressorTypeToZLib"},
        // A zlib header (one block of 32 bytes, 8 compressed) before 8 bytes that are not a zlib stream.
        BadVtk{"zlib_damaged", "m.vtu",
               vtu("AQAAACAAAAAgAAAACAAAAA==AAAAAAAAAAA=", "10", " compressor=\"vtkZLibDataCompressor\"", "binary"), 9,
               "block 1 of 1 of DataArray \"connectivity\" does not decompress"},
        BadVtk{"zlib_huge_block_count", "m.vtu",
               vtu("/////yAAAAAgAAAA", "10", " compressor=\"vtkZLibDataCompressor\"", "binary"), 9,
               "compression header of DataArray \"connectivity\" is damaged"},
        BadVtk{"vtu_not_integer", "m.vtu", vtu("0 1 2 x", "10"), 9, "found \"x\""},
        BadVtk{"vtu_too_few_types", "m.vtu", vtu("0 1 2 3", ""), 11, "holds 0 values, expected 1"},
        BadVtk{"vtu_truncated", "m.vtu", vtu("0 1 2 3", "10").substr(0, 330), 9, "never closed"},
        BadVtk{"vtu_base64_short", "m.vtu", vtu("EAAAAAAAAAA=", "10", "", "binary"), 9,
               "announces 16 bytes but the file holds fewer"},
        // Found by tests/fuzz: a UInt64 byte count near 2^64 was converted through a double that overflowed.
        BadVtk{"vtu_header_near_2_64", "m.vtu", vtu("//////////8=", "10", " header_type=\"UInt64\"", "binary"), 9,
               "announces 18446744073709551615 bytes but the file holds fewer"},
        BadVtk{"polydata_xml", "m.vtu", "<VTKFile type=\"PolyData\">\n</VTKFile>\n", 1, "holds a PolyData"},
        // Counts near the largest integer overflowed the reader's arithmetic: 3 times this NumberOfPoints
        // wraps around to 2, matched the two values given, and the points were read past the array's end.
        BadVtk{"vtu_point_count_wraps", "m.vtu",
               "<VTKFile type=\"UnstructuredGrid\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"6148914691236517206\" "
               "NumberOfCells=\"0\">\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" "
               "format=\"ascii\">1 2</DataArray>\n</Points>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n",
               5, "holds 2 values"},
        // Found by tests/fuzz: a version too large for an int was converted to one.
        BadVtk{"huge_version", "m.vtk", "# vtk DataFile Version 5e59\ntest\nCOMPRESSED\n", 3, "ASCII or BINARY"},
        // A file ending in a newline ends on the (empty) line after its last one: 6 here, 7 below.
        BadVtk{"huge_lookup_table", "m.vtk", kLegacyHead + "LOOKUP_TABLE t 9223372036854775807\n", 6,
               "the file ends while reading the values of a data array"},
        BadVtk{"huge_field_tuples", "m.vtk", kLegacyHead + "FIELD f 1\na 2 9223372036854775807 float\n", 7,
               "the file ends while reading the values of array \"a\""},
        BadVtk{"huge_cell_size", "m.vtk",
               kLegacyHead + "POINTS 1 float\n0 0 0\nCELLS 2 9223372036854775807\n0\n9223372036854775807\n", 9,
               "the cells list more than the 9223372036854775807 integers"}),
    [](const auto& test_case) { return test_case.param.name; });

TEST(VtkFileErrorsAtThePath, UnknownExtension) {
  const auto dir = scratch_dir("vtk_file/extension");
  write_text(dir / "m.vtp", "<VTKFile/>\n");
  const InputError error = read_error("vtk_file", {{"path", "m.vtp"}}, dir);
  EXPECT_EQ(where_of(error), "/test/path");
  EXPECT_NE(message_of(error).find("reads legacy .vtk and XML .vtu"), std::string::npos) << message_of(error);
}

}  // namespace
}  // namespace mtled::test
