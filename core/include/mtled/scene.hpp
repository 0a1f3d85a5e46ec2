#pragma once
// A scene: one JSON file that names a component for each role and gives its parameters. Reading it
// (read_scene) applies --set overrides and remembers where each value sits in the file; validating it
// (validate_scene) loads exactly the plugins it names and collects every problem in one pass.
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mtled/parameters.hpp"
#include "mtled/plugin_catalog.hpp"

namespace mtled {

struct SceneDocument {
  std::filesystem::path file;  // empty when read from a string
  std::string name;            // file name for messages
  json root;
  std::map<std::string, int> lines;    // JSON pointer -> 1-based line of its value in the file
  std::vector<std::string> overrides;  // pointers set with --set

  std::filesystem::path directory() const;
  // "scene.json:14: /materials/0/mu" (or "--set /materials/0/mu"); pointers to absent keys fall back to
  // the line of their closest ancestor.
  std::string locate(const std::string& pointer) const;
};

// Reads and parses a scene; a syntax error or unreadable file throws InputError naming file:line:column.
SceneDocument read_scene(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});
SceneDocument parse_scene(const std::string& text, const std::string& name,
                          const std::vector<std::string>& overrides = {});

// Applies one "--set /json/pointer=value" override; value is JSON if it parses, otherwise a string.
void apply_override(SceneDocument& document, const std::string& assignment);

// The scene's "plugin_paths", resolved against its folder (unchecked: validation reports bad entries).
std::vector<std::filesystem::path> scene_plugin_paths(const SceneDocument& document);

struct ComponentBlock {
  std::string type;
  Parameters parameters;
};

// A section of a scene read and declared by a library outside the kernel ("output": the writers in io/,
// "monitors": the checks in monitors/), validated like the kernel's own sections.
struct SceneSection {
  std::string key;
  const ComponentDeclaration* declaration = nullptr;
};

struct Scene {
  SceneDocument document;
  ComponentBlock mesh;
  ComponentBlock shape_function;
  std::vector<ComponentBlock> materials;
  std::vector<ComponentBlock> boundaries;
  std::optional<ComponentBlock> needle;
  ComponentBlock integrator;
  std::optional<ComponentBlock> volumetric;  // absent: each integration point's own J
  std::optional<ComponentBlock> backend;     // absent: the kernel's own CPU engine
  Parameters discretisation;
  std::map<std::string, Parameters> sections;  // by key, each with its defaults filled in

  // Section `key` (throws std::logic_error when the scene was validated without it).
  const Parameters& section(const std::string& key) const;
};

// The kernel's own section of a scene, declared like components, and its values (Parameters::read).
const ComponentDeclaration& discretisation_declaration();
struct DiscretisationSettings {
  int integration_points_per_tet = 1;
  bool consistent_integration = true;
  std::string precision;
};

// Validates the whole scene, loading only the plugins it names, with the sections given (a scene's other
// top-level keys are problems). Throws InputError listing every problem, each located with SceneDocument::locate.
Scene validate_scene(SceneDocument document, PluginCatalog& catalog, const std::vector<SceneSection>& sections = {});

// Re-locates the JSON pointers of an InputError raised after validation (while building the model).
InputError locate_problems(const InputError& error, const SceneDocument& document);

// JSON Schema of scenes, built from every component in the catalog (loads them all) and the sections given.
json scene_json_schema(PluginCatalog& catalog, const std::vector<SceneSection>& sections = {});

}  // namespace mtled
