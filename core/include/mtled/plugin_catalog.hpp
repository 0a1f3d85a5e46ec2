#pragma once
// Finds plugin files on the search path and loads them on demand: only the components a scene names are
// ever loaded. A plugin file is mtled-<category>-<name>.so, so a scene's "type" maps to its file without
// loading anything. Loading checks the handshake (ABI version, build fingerprint, name) before the plugin
// may register. Libraries stay loaded while anything created from them is alive.
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "mtled/registry.hpp"

namespace mtled {

// The folders searched, in order: --plugin-path folders, the scene's plugin_paths, then MTLED_PLUGIN_PATH
// (colon-separated) if set, otherwise the default: mtled/plugins beside the kernel's own library, libmtled_core.so
// (the install location for an installed mtled, the build tree's plugin folder for a build-tree mtled), so that the
// command line and the Python module find the same plugins.
std::vector<std::filesystem::path> plugin_search_path(const std::vector<std::filesystem::path>& command_line,
                                                      const std::vector<std::filesystem::path>& scene);

// The folder of the kernel's own library, libmtled_core.so (lib/ of the build or install tree).
std::filesystem::path kernel_library_directory();
// mtled's program `name` ("mtled", "mtled-conformance") in the bin/ of the same tree, for whoever runs one as a child
// process (mtled study, mtled fit: also when called from the Python module, whose process is python3).
std::filesystem::path mtled_program(const std::string& name);

class PluginCatalog {
 public:
  struct Available {
    Category category;
    std::string name;
    std::filesystem::path file;
  };

  explicit PluginCatalog(std::vector<std::filesystem::path> search_path);
  ~PluginCatalog();
  PluginCatalog(const PluginCatalog&) = delete;
  PluginCatalog& operator=(const PluginCatalog&) = delete;

  const std::vector<std::filesystem::path>& search_path() const { return search_path_; }
  const std::vector<Available>& available() const { return available_; }
  std::vector<std::string> names(Category category) const;
  const Available* find(Category category, std::string_view name) const;
  // The same component found in two different files: each is a problem naming both files.
  const std::vector<Problem>& duplicates() const { return duplicates_; }

  // Loads the component's plugin unless already loaded. Throws InputError (at `where`) when it is missing,
  // duplicated, refused by the handshake, or its registration fails.
  const ComponentDeclaration& load(Category category, std::string_view name, const std::string& where = "");

  template <class Interface>
  std::shared_ptr<Interface> create(std::string_view name, const Parameters& parameters) {
    auto library = library_for(Interface::category, name);
    std::unique_ptr<Interface> object = registry_.create<Interface>(name, parameters);
    // The object dies before the library that holds its code.
    struct Held {
      std::shared_ptr<void> library;
      std::unique_ptr<Interface> object;
    };
    auto held = std::make_shared<Held>(Held{std::move(library), std::move(object)});
    return std::shared_ptr<Interface>(held, held->object.get());
  }

  // File names of the loaded plugin libraries, in load order.
  std::vector<std::string> loaded_files() const;
  const Registry& registry() const { return registry_; }

 private:
  // Why the build left the component out ("not built: ..."), from left-out.txt in the search path's folders
  // (mtled_left_out_plugin, scripts/gpu-bundle.sh).
  std::optional<std::string> left_out_reason(Category category, std::string_view name) const;
  struct Library;
  std::shared_ptr<void> library_for(Category category, std::string_view name) const;

  std::vector<std::filesystem::path> search_path_;
  std::vector<Available> available_;
  std::vector<Problem> duplicates_;
  std::map<std::pair<Category, std::string>, std::shared_ptr<Library>, std::less<>> loaded_;
  std::vector<std::string> load_order_;
  Registry registry_;  // declared last: destroyed first, while its factories' code is still loaded
};

}  // namespace mtled
