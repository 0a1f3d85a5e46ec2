// The process group of a run (mtled/interfaces/process_group.hpp): one process alone, or the launcher's group
// through the process_group plugin.
#include "mtled/interfaces/process_group.hpp"

#include <fmt/format.h>

#include <cstdlib>

#include "mtled/errors.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/scene.hpp"

namespace mtled {

namespace {

// The launchers mtled recognises: the variable that says how many processes one started, and the prefixes of
// everything it sets (Open MPI's OMPI_ and OPAL_, PMIx's, PMI's).
constexpr const char* kSizeVariables[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"};
constexpr std::string_view kVariablePrefixes[] = {"OMPI_", "OPAL_", "PMIX_", "PMI_"};

class OneProcess final : public ProcessGroup {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  std::string backend() const override { return "cpu"; }
  void barrier() override {}
  void sum_on_first(std::vector<double>&) override {}
  void finish() override {}
};

}  // namespace

ProcessGroup::~ProcessGroup() = default;

int launched_processes() {
  for (const char* name : kSizeVariables)
    if (const char* value = std::getenv(name)) return std::atoi(value);
  return std::getenv("PMIX_RANK") ? 1 : 0;
}

bool launcher_variable(std::string_view entry) {
  for (const std::string_view prefix : kVariablePrefixes)
    if (entry.starts_with(prefix)) return true;
  return false;
}

std::shared_ptr<ProcessGroup> join_process_group(const std::vector<std::filesystem::path>& search_path) {
  const int launched = launched_processes();
  if (launched == 0) return std::make_shared<OneProcess>();
  PluginCatalog catalog(search_path);
  const std::vector<std::string> names = catalog.names(Category::process_group);
  if (names.empty()) {
    if (launched == 1) return std::make_shared<OneProcess>();
    throw InputError("mpirun", fmt::format("no process_group plugin (mtled-process_group-*.so) on the plugin path, so "
                                           "the {} processes would each run the whole scene into the same folder: "
                                           "the mpi plugin is built when CMake finds MPI and METIS (Debian "
                                           "libopenmpi-dev libmetis-dev), rebuild with them; or run without mpirun",
                                           launched));
  }
  // The object holds its library: it outlives this catalog.
  const ComponentDeclaration& declaration = catalog.load(Category::process_group, names.front(), "mpirun");
  return catalog.create<ProcessGroup>(names.front(), Parameters(declaration, json::object(), "/process_group"));
}

void run_across(SceneDocument& document, const ProcessGroup& group) {
  if (group.size() == 1) return;
  json& root = document.root;
  if (!root.contains("backend") || !root["backend"].is_object()) {
    root["backend"] = {{"type", group.backend()}};
    return;
  }
  const std::string named = root["backend"].value("type", group.backend());
  if (named != group.backend())
    throw InputError(document.locate("/backend/type"),
                     fmt::format("the {} backend runs on one process, and this run has {} processes: run without the "
                                 "launcher (mpirun), or leave out /backend (and --backend) to run on the {} backend "
                                 "across them",
                                 named, group.size(), group.backend()));
}

}  // namespace mtled
