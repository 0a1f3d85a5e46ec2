// The same cube in every format gives the same mesh, and every reader's output passes the kernel's
// remove_unused_nodes and check_mesh, as a scene run does with it.
#include <fstream>
#include <iterator>

#include "reader_test_support.hpp"

namespace mtled::test {
namespace {

struct Reading {
  std::string reader;
  json block;
  std::map<std::string, std::string> rename;  // region names of formats that only number regions
};

std::vector<Reading> cube_readings() {
  const std::map<std::string, std::string> numbered = {{"1", "left"}, {"2", "right"}};
  return {{"gmsh_file", {{"path", "cube_msh22.msh"}}, {}},
          {"gmsh_file", {{"path", "cube_msh41.msh"}}, {}},
          // Re-saved binary by Gmsh 4.8 (`-save -bin`): read through Gmsh's own reader.
          {"gmsh_file", {{"path", "cube_msh22_bin.msh"}}, {}},
          {"gmsh_file", {{"path", "cube_msh41_bin.msh"}}, {}},
          {"vtk_file", {{"path", "cube.vtk"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_appended.vtu"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          // Written by VTK 9.1 itself, meshio 5.0 and as 3D Slicer saves models (see tests/data/meshes/README.md).
          {"vtk_file", {{"path", "cube_vtk_zlib.vtu"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_vtk_zlib_raw.vtu"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_vtk_zlib_inline.vtu"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_slicer.vtu"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_slicer.vtk"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_vtk_binary51.vtk"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_meshio.vtu"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"vtk_file", {{"path", "cube_meshio.vtk"}, {"node_set_arrays", {"bottom", "top"}}}, numbered},
          {"abaqus_file", {{"path", "cube.inp"}}, {}}};
}

TEST(CrossFormat, TheCubeIsTheSameMeshInEveryFormat) {
  const CanonicalMesh reference = reference_cube();
  ASSERT_EQ(reference.points.size(), 12u);
  ASSERT_EQ(reference.regions.at("left").size(), 6u);
  for (const auto& reading : cube_readings()) {
    const TetMesh mesh = read_mesh(reading.reader, reading.block);
    EXPECT_EQ(canonical(mesh, reading.rename), reference) << reading.reader << " " << reading.block.dump();
  }
}

TEST(CrossFormat, SlicersCoordinateSystemTagIsKept) {
  // 3D Slicer records the frame of a saved model: "SPACE=LPS" in a legacy file's title line, a string field
  // "SPACE" in a .vtu. Files without it (VTK's, meshio's) leave the mesh untagged.
  for (const std::string file : {"cube_slicer.vtu", "cube_slicer.vtk"})
    EXPECT_EQ(read_mesh("vtk_file", {{"path", file}}).coordinate_system, "LPS") << file;
  for (const std::string file : {"cube_vtk_zlib.vtu", "cube.vtk", "cube_meshio.vtk"})
    EXPECT_EQ(read_mesh("vtk_file", {{"path", file}}).coordinate_system, "") << file;
}

TEST(CrossFormat, EveryReadersMeshPassesCheckMesh) {
  for (const auto& reading : cube_readings()) {
    TetMesh mesh = read_mesh(reading.reader, reading.block);
    remove_unused_nodes(mesh);
    ASSERT_NO_THROW(check_mesh(mesh, true)) << reading.reader << " " << reading.block.dump();
    // After check_mesh every tet is right-handed; the two boxes fill the unit cube (exact in binary
    // arithmetic up to rounding of 12 small sums).
    for (Index t = 0; t < mesh.tet_count(); ++t) EXPECT_GT(tet_volume(mesh, t), 0.0);
    EXPECT_NEAR(total_volume(mesh), 1.0, 1e-14) << reading.reader;
    EXPECT_EQ(mesh.tet_region.size(), mesh.tets.size());
  }
  // Gmsh-made meshes with surface, line and point elements beside the tets, through all three readers.
  for (const auto& [reader, block] :
       std::vector<std::pair<std::string, json>>{{"gmsh_file", {{"path", "cube_gmsh41_all.msh"}}},
                                                 {"gmsh_file", {{"path", "cube_gmsh22.msh"}}},
                                                 {"vtk_file", {{"path", "cube_gmsh.vtk"}}},
                                                 {"abaqus_file", {{"path", "cube_gmsh.inp"}}}}) {
    TetMesh mesh = read_mesh(reader, block);
    remove_unused_nodes(mesh);
    ASSERT_NO_THROW(check_mesh(mesh, true)) << reader << " " << block.dump();
    EXPECT_NEAR(total_volume(mesh), 1.0, 1e-12) << reader << " " << block.dump();
  }
}

TEST(CrossFormat, BinaryGmshFilesGiveTheMeshOfTheAsciiOnes) {
  // One geometry meshed by Gmsh 4.8 and saved four ways: binary files go through Gmsh's reader, ASCII ones
  // through mtled's parser. ASCII .msh holds 16 significant digits, binary the doubles: equal to 1e-15 m here.
  const double quantum = 1e-12;
  const CanonicalMesh ascii = canonical(read_mesh("gmsh_file", {{"path", "cube_gmsh41.msh"}}), {}, quantum);
  EXPECT_EQ(ascii.regions.size(), 2u);
  EXPECT_EQ(ascii.node_sets.size(), 2u);
  for (const std::string file : {"cube_gmsh22.msh", "cube_gmsh22_bin.msh", "cube_gmsh41_bin.msh"})
    EXPECT_EQ(canonical(read_mesh("gmsh_file", {{"path", file}}), {}, quantum), ascii) << file;
}

TEST(CrossFormat, MtledsMshParserAgreesWithGmshsOwnReader) {
  // Gmsh's reader as the independent reference for mtled's: the same nodes, tets, regions and node sets.
  for (const std::string file :
       {"cube_msh22.msh", "cube_msh41.msh", "cube_gmsh22.msh", "cube_gmsh41.msh", "cube_gmsh41_all.msh"})
    EXPECT_EQ(canonical(read_mesh("gmsh_file", {{"path", file}})),
              canonical(read_mesh("gmsh_file", {{"path", file}, {"reader", "gmsh"}})))
        << file;
}

TEST(CrossFormat, DamagedBinaryGmshFilesAreRefusedByName) {
  const auto dir = scratch_dir("cross_format/damaged_binary");
  std::ifstream in(fixtures() / "cube_gmsh41_bin.msh", std::ios::binary);
  const std::string whole((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  write_text(dir / "cut.msh", whole.substr(0, whole.size() / 2));
  write_text(dir / "header_only.msh", "$MeshFormat\n4.1 1 8\n");
  for (const std::string file : {"cut.msh", "header_only.msh"}) {
    const InputError error = read_error("gmsh_file", {{"path", file}}, dir);
    EXPECT_EQ(where_of(error), (dir / file).string());
    EXPECT_NE(message_of(error).find("Gmsh could not read the file"), std::string::npos) << message_of(error);
  }
  // A few bytes changed: Gmsh 4.8.4's reader dies of a segmentation fault on it. It runs in a child process,
  // so the crash is an input error here, and this test process lives on.
  const InputError error = read_error("gmsh_file", {{"path", "cube_gmsh41_bin_damaged.msh"}});
  const std::string message = message_of(error);
  EXPECT_TRUE(message.find("Gmsh's reader crashed on the file") != std::string::npos ||
              message.find("Gmsh could not read the file") != std::string::npos)
      << message;
}

TEST(CrossFormat, EmptyAndMissingFilesInEveryReader) {
  const auto dir = scratch_dir("cross_format/empty");
  for (const auto& [reader, file] : std::vector<std::pair<std::string, std::string>>{
           {"gmsh_file", "m.msh"}, {"vtk_file", "m.vtk"}, {"vtk_file", "m.vtu"}, {"abaqus_file", "m.inp"}}) {
    write_text(dir / file, "");
    InputError error = read_error(reader, {{"path", file}}, dir);
    EXPECT_EQ(where_of(error), (dir / file).string()) << reader;
    EXPECT_NE(message_of(error).find("the mesh file is empty"), std::string::npos) << message_of(error);
    // Missing: the error is at the scene's "path", names the resolved file and suggests the close name.
    error = read_error(reader, {{"path", "n" + file.substr(1)}}, dir);
    EXPECT_EQ(where_of(error), "/test/path") << reader;
    EXPECT_NE(message_of(error).find((dir / ("n" + file.substr(1))).string() + " does not exist"), std::string::npos)
        << message_of(error);
    EXPECT_NE(message_of(error).find("did you mean \"" + file + "\""), std::string::npos) << message_of(error);
  }
}

TEST(CrossFormat, DeclarationsAndExampleBlocks) {
  // Each reader's example names a fixture of this folder by its path from the source tree's root: read with
  // the source tree as the scene's folder, it gives a valid mesh of the unit cube.
  for (const std::string reader : {"gmsh_file", "vtk_file", "abaqus_file"}) {
    const ComponentDeclaration& declaration = catalog().load(Category::mesh, reader);
    EXPECT_FALSE(declaration.summary().empty()) << reader;
    for (const auto& spec : declaration.parameters()) {
      EXPECT_FALSE(spec.doc.empty()) << reader << "." << spec.name;
      EXPECT_FALSE(spec.unit.empty()) << reader << "." << spec.name;
    }
    ASSERT_FALSE(declaration.example().contains("type")) << reader;
    TetMesh mesh = read_mesh(reader, declaration.example(), source_dir());
    remove_unused_nodes(mesh);
    ASSERT_NO_THROW(check_mesh(mesh, true)) << reader;
    EXPECT_NEAR(total_volume(mesh), 1.0, 1e-12) << reader;
  }
}

}  // namespace
}  // namespace mtled::test
