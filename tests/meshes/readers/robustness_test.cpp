// A damaged file must give an InputError, never a crash or another exception: every fixture cut short at
// many places, and with single bytes replaced by characters that matter to the formats.
#include <random>

#include "mtled/log.hpp"
#include "reader_test_support.hpp"

namespace mtled::test {
namespace {

struct Fixture {
  std::string file;
  std::string reader;
};

const std::vector<Fixture> kFixtures = {
    {"cube_msh22.msh", "gmsh_file"}, {"cube_msh41.msh", "gmsh_file"},   {"cube_gmsh41_all.msh", "gmsh_file"},
    {"cube.vtk", "vtk_file"},        {"cube_v51.vtk", "vtk_file"},      {"cube.vtu", "vtk_file"},
    {"cube_binary.vtu", "vtk_file"}, {"cube_appended.vtu", "vtk_file"}, {"cube_raw.vtu", "vtk_file"},
    {"cube.inp", "abaqus_file"},     {"cube_gmsh.inp", "abaqus_file"}};

// Loads the damaged text; returns "" when it was read or refused with an InputError, else what went wrong.
std::string load_damaged(MeshSource& source, const std::filesystem::path& dir, const std::string& file,
                         const std::string& text) {
  write_text(dir / file, text);
  try {
    TetMesh mesh = source.load(MeshContext{dir, 1, {}});
    // What a reader accepts must have valid indices (check_mesh may still refuse its geometry).
    for (const auto& tet : mesh.tets)
      for (Index v : tet)
        if (v < 0 || v >= mesh.node_count()) return "a tet index out of range";
    if (mesh.tet_region.size() != mesh.tets.size()) return "tet_region does not match the tets";
    for (Index r : mesh.tet_region)
      if (r < 0 || static_cast<std::size_t>(r) >= mesh.region_names.size()) return "a region index out of range";
    for (const auto& [name, nodes] : mesh.node_sets)
      for (Index n : nodes)
        if (n < 0 || n >= mesh.node_count()) return "node set " + name + " has an index out of range";
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    return std::string("not an InputError: ") + e.what();
  }
  return "";
}

// The damaged files' warnings ("tets in no region") are expected: keep them out of the test output.
class Robustness : public ::testing::Test {
 protected:
  void SetUp() override {
    level_ = log().level();
    log().set_level(spdlog::level::err);
  }
  void TearDown() override { log().set_level(level_); }

 private:
  spdlog::level::level_enum level_ = spdlog::level::info;
};

TEST_F(Robustness, CutShortFilesGiveInputErrors) {
  for (const auto& fixture : kFixtures) {
    const std::string text = read_text(fixtures() / fixture.file);
    const auto dir = scratch_dir("robustness/cut");
    const auto source = make<MeshSource>(fixture.reader, {{"path", fixture.file}});
    // Every 5th byte: lands inside numbers, keywords, tags, base64 groups and raw binary alike.
    for (std::size_t cut = 0; cut < text.size(); cut += 5) {
      const std::string problem = load_damaged(*source, dir, fixture.file, text.substr(0, cut));
      EXPECT_EQ(problem, "") << fixture.file << " cut at byte " << cut;
      if (!problem.empty()) break;
    }
  }
}

TEST_F(Robustness, CorruptedBytesGiveInputErrors) {
  const std::string replacements = "09-.+eE$*,\n x<>\"=/_%\t";
  std::mt19937 random(2024);
  for (const auto& fixture : kFixtures) {
    const std::string text = read_text(fixtures() / fixture.file);
    const auto dir = scratch_dir("robustness/corrupt");
    const auto source = make<MeshSource>(fixture.reader, {{"path", fixture.file}});
    std::uniform_int_distribution<std::size_t> position(0, text.size() - 1);
    std::uniform_int_distribution<std::size_t> replacement(0, replacements.size() - 1);
    for (int trial = 0; trial < 200; ++trial) {
      std::string damaged = text;
      const std::size_t at = position(random);
      damaged[at] = replacements[replacement(random)];
      const std::string problem = load_damaged(*source, dir, fixture.file, damaged);
      EXPECT_EQ(problem, "") << fixture.file << " with byte " << at << " set to '" << damaged[at] << "'";
      if (!problem.empty()) break;
    }
  }
}

}  // namespace
}  // namespace mtled::test
