#pragma once
// Helpers for the test suites: the build tree's plugins through the real loader, components built from
// JSON parameter blocks, small structured meshes, and running the mtled executable.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "mtled/force_kernel.hpp"
#include "mtled/mesh.hpp"
#include "mtled/plugin_catalog.hpp"

namespace mtled::test {

std::filesystem::path source_dir();
std::filesystem::path binary_dir();
std::filesystem::path plugin_dir();
// A fresh, empty folder for a test's files (under the build tree).
std::filesystem::path scratch_dir(const std::string& name);

// One catalog over the build tree's plugin folder, shared by the whole test executable.
PluginCatalog& catalog();

// Validates `block` against the component's declaration (failing the test on any problem) and returns
// the parameters.
Parameters parameters(Category category, const std::string& name, const json& block);

template <class Interface>
std::shared_ptr<Interface> make(const std::string& name, const json& block) {
  const Parameters p = parameters(Interface::category, name, block);
  return catalog().create<Interface>(name, p);
}

// One OpenMP thread for the scope: small clouds run fastest on one thread (and a shared CI machine does not
// stall on OpenMP barriers).
class OneThread {
 public:
  OneThread();
  ~OneThread();
  OneThread(const OneThread&) = delete;
  OneThread& operator=(const OneThread&) = delete;

 private:
  int saved_;
};

// A box [0,a]x[0,b]x[0,c] split into n_x n_y n_z cubes of 6 tets each; interior nodes moved at random by up
// to `jitter` times the cell size (seeded, repeatable). Node sets "x0", "x1", "y0", "y1", "z0", "z1" hold
// the faces.
TetMesh box_mesh(Vec3 size, int nx, int ny, int nz, double jitter = 0.0, unsigned seed = 1);

// A discretisation and the force kernel on it, as a MechanicalSystem builds them, for tests that need no scene.
struct Discretised {
  Discretised(TetMesh mesh, std::shared_ptr<const ShapeFunctions> shape_functions,
              std::vector<std::shared_ptr<const Material>> materials, Discretisation::Options options,
              std::shared_ptr<VolumetricTreatment> volumetric = nullptr)
      : discretisation(std::move(mesh), std::move(shape_functions), std::move(materials), std::move(options)),
        kernel(discretisation, std::move(volumetric)) {}
  Discretisation discretisation;
  ForceKernel kernel;
};

// The interpolated displacement at every node (3 per node) of the nodal parameters u.
inline std::vector<double> interpolated(const Discretisation& discretisation, std::span<const double> u) {
  std::vector<double> out(u.size());
  discretisation.interpolate(u, out);
  return out;
}

// A small cylinder of the paper's gel for the needle models' tests: r = 6 mm, height `height`, about 600
// nodes (spacing 1.3 mm), Ogden mu = 722 Pa, alpha = -1.3, bottom fixed, MMLS, dynamic relaxation over 300
// linear load steps to a tolerance of 1e-3; `needle` is the scene's needle block.
json gel_cylinder_scene(double height, const json& needle);

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};
// Runs the mtled executable with `arguments`; `environment` entries are set for the child ("NAME=value";
// "NAME=" unsets); `launcher` goes before the executable (mpirun -np 2, timeout 60, ...).
CommandResult run_mtled(const std::vector<std::string>& arguments, const std::vector<std::string>& environment = {},
                        const std::vector<std::string>& launcher = {});

// A CSV file as rows of fields (no quoting: the files mtled writes have none in these tests' labels).
std::vector<std::vector<std::string>> read_csv(const std::filesystem::path& file);

// Reads a whole file / parses a JSON file.
std::string read_text(const std::filesystem::path& file);
json read_json(const std::filesystem::path& file);
void write_text(const std::filesystem::path& file, const std::string& text);

}  // namespace mtled::test
