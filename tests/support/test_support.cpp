#include "test_support.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace mtled::test {

OneThread::OneThread() : saved_(omp_get_max_threads()) { omp_set_num_threads(1); }
OneThread::~OneThread() { omp_set_num_threads(saved_); }

namespace {
// The build tree's paths, unless the environment names others: a test binary copied into a relocatable bundle
// (scripts/gpu-bundle.sh) runs where that build tree does not exist.
fs::path configured(const char* variable, const char* built_in) {
  const char* value = std::getenv(variable);
  return value != nullptr && *value != '\0' ? fs::path(value) : fs::path(built_in);
}
}  // namespace

fs::path source_dir() { return configured("MTLED_TEST_SOURCE_DIR", MTLED_TEST_SOURCE_DIR); }
fs::path binary_dir() { return configured("MTLED_TEST_BINARY_DIR", MTLED_TEST_BINARY_DIR); }
fs::path plugin_dir() { return configured("MTLED_TEST_PLUGIN_DIR", MTLED_TEST_PLUGIN_DIR); }

fs::path scratch_dir(const std::string& name) {
  // ctest runs each test in its own process, in parallel: the folder is unique to the running test.
  fs::path dir = binary_dir() / "test-output" / name;
  if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info())
    dir /= fmt::format("{}.{}", info->test_suite_name(), info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

PluginCatalog& catalog() {
#ifdef MTLED_CONFORMANCE_RUNNER
  // The installed runner searches as mtled does (MTLED_PLUGIN_PATH, which `mtled conformance` sets to the
  // plugin's folder and the usual path, else lib/mtled/plugins beside it).
  static PluginCatalog instance(plugin_search_path({}, {}));
#else
  static PluginCatalog instance({plugin_dir()});
#endif
  return instance;
}

Parameters parameters(Category category, const std::string& name, const json& block) {
  const ComponentDeclaration& declaration = catalog().load(category, name);
  std::vector<Problem> problems;
  Parameters p = validate_parameters(declaration, block, "/test", problems, {"type"});
  for (const auto& problem : problems) ADD_FAILURE() << name << ": " << problem.format();
  return p;
}

TetMesh box_mesh(Vec3 size, int nx, int ny, int nz, double jitter, unsigned seed) {
  TetMesh mesh;
  mesh.source = "test box";
  const int n[3] = {nx, ny, nz};
  auto id = [&](int i, int j, int k) { return static_cast<Index>(i + (nx + 1) * (j + (ny + 1) * k)); };
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const Vec3 h(size[0] / nx, size[1] / ny, size[2] / nz);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        Vec3 x(i * h[0], j * h[1], k * h[2]);
        const int index[3] = {i, j, k};
        for (int d = 0; d < 3; ++d) {
          const double shift = jitter * h[d] * uniform(random);
          if (index[d] > 0 && index[d] < n[d]) x[d] += shift;  // boundary nodes stay on their faces
        }
        mesh.points.push_back(x);
      }
  // Kuhn triangulation: 6 tets per cube sharing the main diagonal, consistent across faces.
  static constexpr int kPaths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& path : kPaths) {
          std::array<int, 3> c{i, j, k};
          std::array<Index, 4> tet{};
          tet[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[path[s]];
            tet[s + 1] = id(c[0], c[1], c[2]);
          }
          mesh.tets.push_back(tet);
        }
  mesh.tet_region.assign(mesh.tets.size(), 0);
  mesh.region_names = {"all"};
  const char* names[3][2] = {{"x0", "x1"}, {"y0", "y1"}, {"z0", "z1"}};
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const int index[3] = {i, j, k};
        for (int d = 0; d < 3; ++d) {
          if (index[d] == 0) mesh.node_sets[names[d][0]].push_back(id(i, j, k));
          if (index[d] == n[d]) mesh.node_sets[names[d][1]].push_back(id(i, j, k));
        }
      }
  // Orients the tets. A strong jitter can fold a few tets over their neighbours: harmless for the node clouds
  // these meshes stand for, so overlaps are allowed here (scenes refuse them).
  check_mesh(mesh, /*fix_orientation=*/true, /*allow_overlaps=*/jitter > 0.0);
  return mesh;
}

json gel_cylinder_scene(double height, const json& needle) {
  return {{"mesh", {{"type", "cylinder"}, {"radius", 0.006}, {"height", height}, {"target_nodes", 600}}},
          {"shape_function", {{"type", "mmls"}}},
          {"materials", {{{"type", "ogden"}, {"mu", 722}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 1000}}}},
          {"boundaries", {{{"type", "fixed"}, {"name", "bottom"}, {"nodes", {{"group", "bottom"}}}}}},
          {"needle", needle},
          {"integrator",
           {{"type", "dynamic_relaxation"}, {"load_steps", 300}, {"load_curve", "linear"}, {"tolerance", 1e-3}}}};
}

CommandResult run_mtled(const std::vector<std::string>& arguments, const std::vector<std::string>& environment,
                        const std::vector<std::string>& launcher) {
  auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  std::string command = "env";
  for (const auto& e : environment) {
    if (!e.empty() && e.back() == '=') {
      command += " -u " + quote(e.substr(0, e.size() - 1));
    } else {
      command += " " + quote(e);
    }
  }
  for (const auto& word : launcher) command += " " + quote(word);
  command += " " + quote(configured("MTLED_TEST_EXECUTABLE", MTLED_EXECUTABLE).string());
  for (const auto& a : arguments) command += " " + quote(a);
  command += " 2>&1";
  CommandResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

json read_json(const fs::path& file) { return json::parse(read_text(file)); }

std::vector<std::vector<std::string>> read_csv(const fs::path& file) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(read_text(file));
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::string field;
    std::istringstream cells(line);
    while (std::getline(cells, field, ',')) fields.push_back(field);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    rows.push_back(fields);
  }
  return rows;
}

void write_text(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

}  // namespace mtled::test
