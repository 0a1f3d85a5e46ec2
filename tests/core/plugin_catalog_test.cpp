// The plugin loader: only named plugins load; mismatched, duplicated, missing or failing plugins are
// refused with messages that say what differs and where.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "mtled/plugin_catalog.hpp"
#include "mtled/version.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

const fs::path kBad = MTLED_TEST_BAD_PLUGIN_DIR;

std::string load_error(PluginCatalog& catalog, const std::string& name) {
  try {
    catalog.load(Category::material, name, "/materials/0/type");
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems().at(0).where, "/materials/0/type");
    return e.what();
  }
  ADD_FAILURE() << name << " was loaded but should have been refused";
  return "";
}

TEST(PluginCatalog, FindsPluginsByFileNameWithoutLoadingThem) {
  PluginCatalog catalog({test::plugin_dir()});
  EXPECT_NE(catalog.find(Category::integrator, "dynamic_relaxation"), nullptr);
  EXPECT_NE(catalog.find(Category::boundary, "fixed"), nullptr);
  EXPECT_TRUE(catalog.loaded_files().empty());
  catalog.load(Category::boundary, "fixed");
  EXPECT_EQ(catalog.loaded_files(), std::vector<std::string>{"mtled-boundary-fixed.so"});
}

TEST(PluginCatalog, RefusesAnotherAbiVersion) {
  PluginCatalog catalog({kBad / "abi"});
  const std::string message = load_error(catalog, "abi_mismatch");
  EXPECT_NE(message.find("built for mtled ABI version 999"), std::string::npos) << message;
  EXPECT_NE(message.find("this mtled has ABI version " + std::to_string(MTLED_ABI_VERSION)), std::string::npos) << message;
  EXPECT_NE(message.find("mtled-material-abi_mismatch.so"), std::string::npos) << message;
}

TEST(PluginCatalog, RefusesAnotherBuildFingerprintAndSaysWhatDiffers) {
  PluginCatalog catalog({kBad / "fingerprint"});
  const std::string message = load_error(catalog, "fingerprint_mismatch");
  EXPECT_NE(message.find("eigen_max_static_align_bytes: plugin 0, kernel"), std::string::npos) << message;
}

TEST(PluginCatalog, DuplicateComponentNamesBothFiles) {
  // Another build of the same component (here: the library with bytes appended, so its contents differ).
  const auto other = test::scratch_dir("plugin_catalog/other_build");
  fs::copy_file(kBad / "good" / "mtled-material-good_test_material.so", other / "mtled-material-good_test_material.so");
  std::ofstream(other / "mtled-material-good_test_material.so", std::ios::app | std::ios::binary) << "another build";
  PluginCatalog catalog({kBad / "good", other});
  ASSERT_EQ(catalog.duplicates().size(), 1u);
  const std::string message = load_error(catalog, "good_test_material");
  EXPECT_NE(message.find((kBad / "good").string()), std::string::npos) << message;
  EXPECT_NE(message.find(other.string()), std::string::npos) << message;
}

TEST(PluginCatalog, AnIdenticalCopyInASecondFolderIsNoDuplicate) {
  // A plugin's build folder on the command line and a copy of the library beside the scene: one plugin.
  const auto copy = test::scratch_dir("plugin_catalog/identical_copy");
  fs::copy_file(kBad / "good" / "mtled-material-good_test_material.so", copy / "mtled-material-good_test_material.so");
  PluginCatalog catalog({kBad / "good", copy});
  EXPECT_TRUE(catalog.duplicates().empty());
  EXPECT_NO_THROW(catalog.load(Category::material, "good_test_material"));
  EXPECT_EQ(catalog.loaded_files(), std::vector<std::string>{"mtled-material-good_test_material.so"});
}

TEST(PluginCatalog, UnknownComponentSuggestsTheClosestAndListsFolders) {
  PluginCatalog catalog({kBad / "good"});
  const std::string message = load_error(catalog, "good_test_materal");
  EXPECT_NE(message.find("did you mean \"good_test_material\"?"), std::string::npos) << message;
  EXPECT_NE(message.find((kBad / "good").string()), std::string::npos) << message;
}

// A component the build left out (left-out.txt, written by CMake's mtled_left_out_plugin) is named with the reason,
// not only as unknown.
TEST(PluginCatalog, AComponentTheBuildLeftOutSaysWhy) {
  const fs::path folder = test::scratch_dir("catalog-left-out");
  std::ofstream(folder / "left-out.txt") << "material other_law: not built: it needs -DWITH_OTHER=ON\n"
                                         << "material absent_law: not built: it needs libabsent. Use ogden\n";
  PluginCatalog catalog({folder});
  const std::string message = load_error(catalog, "absent_law");
  EXPECT_NE(message.find("unknown material \"absent_law\""), std::string::npos) << message;
  EXPECT_NE(message.find("; not built: it needs libabsent. Use ogden"), std::string::npos) << message;
  EXPECT_EQ(load_error(catalog, "never_built").find("not built"), std::string::npos);
}

TEST(PluginCatalog, ObjectsKeepTheirLibraryLoaded) {
  std::shared_ptr<Material> material;
  {
    PluginCatalog catalog({kBad / "good"});
    const ComponentDeclaration& d = catalog.load(Category::material, "good_test_material");
    ASSERT_NE(d.find("region"), nullptr) << "the kernel's common material parameter joins the declaration";
    std::vector<Problem> problems;
    material = catalog.create<Material>("good_test_material", validate_parameters(d, {{"modulus", 5.0}}, "/m", problems));
  }
  // The catalog is gone; the library must still be loaded for the object to work and be destroyed.
  Mat3 S;
  ASSERT_TRUE(material->stress(2.0 * Mat3::Identity(), S));
  EXPECT_DOUBLE_EQ(S(0, 0), 0.5 * 5.0 * 3.0);
  material.reset();
}

TEST(PluginCatalog, AFactoryThatThrowsSurfacesAsAnException) {
  PluginCatalog catalog({kBad / "throws"});
  const ComponentDeclaration& d = catalog.load(Category::material, "throws_when_built");
  std::vector<Problem> problems;
  const Parameters p = validate_parameters(d, json::object(), "/m", problems);
  try {
    catalog.create<Material>("throws_when_built", p);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("deliberate failure"), std::string::npos);
  }
}

TEST(PluginSearchPath, EnvironmentReplacesTheDefault) {
  ::unsetenv("MTLED_PLUGIN_PATH");
  auto path = plugin_search_path({"/cli"}, {"/scene"});
  ASSERT_EQ(path.size(), 3u);
  EXPECT_EQ(path[0], fs::path("/cli"));
  EXPECT_EQ(path[1], fs::path("/scene"));
  // The build tree's plugin folder, found from the kernel library's folder (not this test program's).
  EXPECT_EQ(fs::weakly_canonical(path[2]), fs::weakly_canonical(MTLED_TEST_PLUGIN_DIR));
  ::setenv("MTLED_PLUGIN_PATH", "/a:/b", 1);
  path = plugin_search_path({}, {});
  EXPECT_EQ(path, (std::vector<fs::path>{"/a", "/b"}));
  ::unsetenv("MTLED_PLUGIN_PATH");
}

TEST(PluginSearchPath, ProgramsAreFoundInTheBinFolderOfTheKernelLibrarysTree) {
  // This test program is not mtled, yet mtled is found: the build tree's, as CMake built it.
  EXPECT_EQ(fs::weakly_canonical(mtled_program("mtled")), fs::weakly_canonical(MTLED_EXECUTABLE));
}

}  // namespace
}  // namespace mtled
