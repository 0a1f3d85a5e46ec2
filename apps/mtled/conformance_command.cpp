// mtled conformance LIB: runs the installed conformance suites (materials, shape functions, integrators) on a
// plugin library, so that a third party checks their component exactly as mtled checks its own. The suites
// are the test suite's own (tests/materials, tests/shapefunctions, tests/solver), built into the
// mtled-conformance runner beside this executable.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin_catalog.hpp"

namespace fs = std::filesystem;

namespace mtled::app {

namespace {

// The components a library (or every library in a folder) holds, as the catalog names them from the files.
std::vector<std::string> component_names(const fs::path& target) {
  std::error_code ec;
  const bool folder = fs::is_directory(target, ec);
  const PluginCatalog catalog({folder ? target : target.parent_path()});
  std::vector<std::string> names;
  for (const auto& available : catalog.available())
    if (folder || fs::equivalent(available.file, target, ec)) names.push_back(available.name);
  return names;
}

}  // namespace

int conformance_command(const ConformanceOptions& options, const std::vector<fs::path>& plugin_paths) {
  std::error_code ec;
  if (!fs::exists(options.library, ec))
    throw InputError(options.library.string(), "no such plugin library or folder");
  const auto names = component_names(options.library);
  if (names.empty())
    throw InputError(options.library.string(),
                     "not an mtled plugin: its file name must be mtled-CATEGORY-NAME.so (as mtled_add_plugin() "
                     "names it), or a folder holding such files");
  const fs::path runner = mtled_program("mtled-conformance");
  if (!fs::exists(runner, ec))
    throw std::runtime_error(fmt::format("{} is missing: this mtled was built without its conformance runner "
                                         "(MTLED_BUILD_CONFORMANCE_RUNNER=OFF)",
                                         runner.string()));
  // The library's folder first, then the usual search path (--plugin-path, MTLED_PLUGIN_PATH or the default
  // folder), so that the suites also find the shape function and mesh sources a test needs: handed to the
  // runner as its MTLED_PLUGIN_PATH, which its catalog searches as mtled's does.
  std::vector<fs::path> first = {fs::is_directory(options.library, ec) ? options.library : options.library.parent_path()};
  first.insert(first.end(), plugin_paths.begin(), plugin_paths.end());
  std::vector<std::string> folders;
  for (const auto& folder : plugin_search_path(first, {})) folders.push_back(fs::absolute(folder).string());
  setenv("MTLED_PLUGIN_PATH", fmt::format("{}", fmt::join(folders, ":")).c_str(), 1);
  // Every test instantiated for one of the library's components: suites name them ".../NAME" (shape
  // functions also ".../NAME_variant").
  std::vector<std::string> filters;
  for (const auto& name : names) filters.insert(filters.end(), {"*/" + name, "*/" + name + "_*"});
  const std::string filter = fmt::format("--gtest_filter={}", fmt::join(filters, ":"));
  log().info("conformance of {} ({}) with {}", options.library.string(), fmt::join(names, ", "), runner.string());
  std::vector<std::string> arguments = {runner.string(), filter};
  if (!options.gtest_arguments.empty())
    arguments.insert(arguments.end(), options.gtest_arguments.begin(), options.gtest_arguments.end());
  std::vector<char*> argv;
  for (auto& a : arguments) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(nullptr);
  execv(runner.c_str(), argv.data());
  throw std::runtime_error(fmt::format("cannot start {}", runner.string()));
}

}  // namespace mtled::app
