#pragma once
// One declaration per component: every parameter's type, default (or required), unit, allowed range and
// doc. The same declaration drives scene validation, `mtled plugins --describe`, `mtled schema`, the
// generated parameter reference (docs/parameters.md) and the conformance tests.
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeinfo>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/json.hpp"
#include "mtled/types.hpp"

namespace mtled {

// What a component is for. Each category has its own interface in mtled/interfaces/ and its own place in
// a scene (or none: a process group is the launcher's, not the scene's). `scene` is the kernel's own sections
// (discretisation, output).
enum class Category {
  mesh,
  shape_function,
  material,
  boundary,
  needle,
  integrator,
  volumetric,
  backend,
  process_group,
  scene
};

// How many blocks of a category a scene holds under its key; `none`: the category has no place in a scene.
enum class SceneBlocks { one, optional_one, list, non_empty_list, none };

// Every plugin category, once: its name (the CMake CATEGORY, and <category> in the plugin file names
// mtled-<category>-<type>.so), the scene key its blocks go under, and how many. Scene validation, the scene's JSON
// schema, the plugin catalog, CMake's mtled_add_plugin (through MTLED_PLUGIN's check) and `mtled plugins` read this
// table; a new category is a value of Category, a row here and its interface (mtled/interfaces/), with the Scene
// member it is read into if it has a scene key.
struct CategoryInfo {
  Category category;
  std::string_view name;
  std::string_view scene_key;
  SceneBlocks blocks;
};
inline constexpr CategoryInfo kPluginCategories[] = {
    {Category::mesh, "mesh", "mesh", SceneBlocks::one},
    {Category::shape_function, "shape_function", "shape_function", SceneBlocks::one},
    {Category::material, "material", "materials", SceneBlocks::non_empty_list},
    {Category::boundary, "boundary", "boundaries", SceneBlocks::list},
    {Category::needle, "needle", "needle", SceneBlocks::optional_one},
    {Category::integrator, "integrator", "integrator", SceneBlocks::one},
    {Category::volumetric, "volumetric", "volumetric", SceneBlocks::optional_one},
    {Category::backend, "backend", "backend", SceneBlocks::optional_one},
    {Category::process_group, "process_group", "", SceneBlocks::none}};

std::string_view to_string(Category category);

// For the compile-time check in MTLED_PLUGIN that a plugin's interface matches its CMake CATEGORY.
constexpr Category category_from_literal(std::string_view text) {
  for (const CategoryInfo& info : kPluginCategories)
    if (info.name == text) return info.category;
  return Category::scene;
}
std::optional<Category> category_from_string(std::string_view text);
const std::vector<Category>& plugin_categories();
// The table's row of a plugin category (not Category::scene).
const CategoryInfo& category_info(Category category);

// `file`: a path (a string in the scene); a relative one is taken from the scene file's folder when the scene is
// validated, which also checks that the file exists, so a component reads Parameters::file as an absolute path.
// `number_map`: an object of named numbers ({"brain_stem": 0.0012}), each in the spec's range; the names are the
// component's to check (regions, segments).
enum class ParameterType {
  number,
  integer,
  boolean,
  string,
  vector3,
  number_list,
  string_list,
  node_set,
  file,
  number_map
};

std::string_view to_string(ParameterType type);

// Allowed values of a number (or of each entry of a number list). Vectors use `nonzero` for |v| > 0.
struct NumericRange {
  std::optional<double> min, max;
  bool min_exclusive = false;
  bool max_exclusive = false;
  bool nonzero = false;

  bool contains(double value) const;
  bool unbounded() const { return !min && !max && !nonzero; }
  std::string describe() const;  // "> 0", "[0, 1]", "!= 0", "any"
};

// The syntax of a structured value that its own component checks (a node selector, node_selector.hpp): the parameter
// layer calls `check` when a scene is validated (problems with pointers below `where`) and shows `schema` in
// `mtled schema`, without knowing the syntax itself.
struct ValueSyntax {
  std::function<bool(const json& value, const std::string& where, std::vector<Problem>& problems)> check;
  json schema;
};

class Parameters;

// A parameter bound to a member of a component's settings struct (ParameterBuilder::to): Parameters::read<Settings>
// fills every member bound to Settings, so that a component writes each parameter's name once, where it declares
// it (as FEBio's ADD_PARAMETER binds the member it fills). Plain pointers into the plugin's code: nothing of it runs
// or is destroyed after the plugin is unloaded.
struct ParameterBinding {
  const std::type_info* settings = nullptr;
  void (*assign)(void* settings, const Parameters& values, std::string_view name) = nullptr;
};

struct ParameterSpec {
  std::string name;
  ParameterType type = ParameterType::number;
  std::optional<json> default_value;  // used when the key is absent
  bool required = true;               // false when there is a default or the parameter is optional
  std::string unit;                   // SI unit ("Pa", "1/Pa", "m", "kg/m^3", "s"), "1" if dimensionless
  NumericRange range;
  std::vector<json> choices;  // allowed values (strings, string-list entries, integers)
  std::string doc;
  ValueSyntax syntax;  // a node_set's: NodeSelector::syntax()
  ParameterBinding binding;

  json to_json() const;         // for `mtled plugins --json`
  json to_json_schema() const;  // for `mtled schema`
};

class ParameterBuilder {
 public:
  explicit ParameterBuilder(ParameterSpec& spec) : spec_(spec) {}
  ParameterBuilder& doc(std::string text);
  ParameterBuilder& unit(std::string unit);
  ParameterBuilder& defaults(json value);
  ParameterBuilder& optional();  // may be absent: bound to a std::optional member
  ParameterBuilder& positive();
  ParameterBuilder& non_negative();
  ParameterBuilder& nonzero();
  ParameterBuilder& at_least(double value);
  ParameterBuilder& greater_than(double value);
  ParameterBuilder& at_most(double value);
  ParameterBuilder& less_than(double value);
  ParameterBuilder& between(double low, double high);  // inclusive
  ParameterBuilder& choices(std::vector<json> allowed);
  // Binds the parameter to `member` of a settings struct, which Parameters::read fills: a number to double, an
  // integer to long or int, a boolean to bool, a string to std::string, a vector3 to Vec3, a number_list to
  // std::vector<double>, a number_map to std::map<std::string, double>, a string_list to std::vector<std::string>,
  // a file to std::filesystem::path; an optional() one to std::optional of these.
  template <auto member>
  ParameterBuilder& to();

 private:
  ParameterSpec& spec_;
};

class ComponentDeclaration {
 public:
  ComponentDeclaration() = default;
  ComponentDeclaration(std::string name, Category category) : name_(std::move(name)), category_(category) {}

  ComponentDeclaration& summary(std::string text);
  // A working parameter block (without "type"): shown by `mtled plugins --describe`, used by the
  // conformance tests to build every component of a category.
  ComponentDeclaration& example(json block);
  ParameterBuilder number(std::string name);
  ParameterBuilder integer(std::string name);
  ParameterBuilder boolean(std::string name);
  ParameterBuilder string(std::string name);
  ParameterBuilder vector3(std::string name);
  ParameterBuilder number_list(std::string name);
  ParameterBuilder number_map(std::string name);
  ParameterBuilder string_list(std::string name);
  ParameterBuilder node_set(std::string name, ValueSyntax syntax);  // syntax: NodeSelector::syntax()
  ParameterBuilder file(std::string name);
  ComponentDeclaration& add(ParameterSpec spec);  // a spec built elsewhere (the kernel's common parameters)

  const std::string& name() const { return name_; }
  Category category() const { return category_; }
  const std::string& summary() const { return summary_; }
  const json& example() const { return example_; }
  const std::vector<ParameterSpec>& parameters() const { return parameters_; }
  const ParameterSpec* find(std::string_view name) const;

  json to_json() const;         // name, category, summary, parameters
  json to_json_schema() const;  // object schema with "type" fixed to the name

 private:
  ParameterBuilder add_new(std::string name, ParameterType type);
  std::string name_;
  Category category_ = Category::scene;
  std::string summary_;
  json example_ = json::object();
  std::vector<ParameterSpec> parameters_;
};

// A component's validated parameter values, defaults filled in. Getters of undeclared names or of the
// wrong type are programming errors (std::logic_error), never user errors.
class Parameters {
 public:
  Parameters() = default;
  Parameters(const ComponentDeclaration& declaration, json values, std::string pointer);

  const std::string& component() const { return component_; }
  const std::string& pointer() const { return pointer_; }     // "/materials/0"
  std::string pointer(std::string_view name) const;           // "/materials/0/mu"
  bool has(std::string_view name) const;                      // present (given or defaulted)
  const json& values() const { return values_; }

  double number(std::string_view name) const;
  long integer(std::string_view name) const;
  bool boolean(std::string_view name) const;
  std::string string(std::string_view name) const;
  Vec3 vector3(std::string_view name) const;
  std::vector<double> number_list(std::string_view name) const;
  std::map<std::string, double> number_map(std::string_view name) const;
  std::vector<std::string> string_list(std::string_view name) const;
  std::filesystem::path file(std::string_view name) const;  // as validate_scene resolved it


  // The settings struct whose members the declaration bound (ParameterBuilder::to), filled; members bound to no
  // parameter keep their default initialisers.
  template <class Settings>
  Settings read() const;
  // One value by name, as the type of the member it is bound to (ParameterBuilder::to).
  template <class Value>
  Value get(std::string_view name) const;

 private:
  const json& value(std::string_view name, ParameterType expected) const;
  std::string component_;
  std::string pointer_;
  json values_ = json::object();
  std::vector<std::pair<std::string, ParameterType>> types_;
  std::vector<std::pair<std::string, ParameterBinding>> bindings_;
};

namespace detail {
template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};
template <class T>
struct member_of;
template <class Settings, class Value>
struct member_of<Value Settings::*> {
  using settings = Settings;
  using value = Value;
};
}  // namespace detail

template <class Value>
Value Parameters::get(std::string_view name) const {
  if constexpr (detail::is_optional<Value>::value) {
    if (!has(name)) return std::nullopt;
    return get<typename Value::value_type>(name);
  } else if constexpr (std::is_same_v<Value, double>) {
    return number(name);
  } else if constexpr (std::is_same_v<Value, long>) {
    return integer(name);
  } else if constexpr (std::is_same_v<Value, int>) {
    return static_cast<int>(integer(name));
  } else if constexpr (std::is_same_v<Value, bool>) {
    return boolean(name);
  } else if constexpr (std::is_same_v<Value, std::string>) {
    return string(name);
  } else if constexpr (std::is_same_v<Value, Vec3>) {
    return vector3(name);
  } else if constexpr (std::is_same_v<Value, std::vector<double>>) {
    return number_list(name);
  } else if constexpr (std::is_same_v<Value, std::map<std::string, double>>) {
    return number_map(name);
  } else if constexpr (std::is_same_v<Value, std::vector<std::string>>) {
    return string_list(name);
  } else {
    static_assert(std::is_same_v<Value, std::filesystem::path>, "no parameter type reads into this member's type");
    return file(name);
  }
}

template <class Settings>
Settings Parameters::read() const {
  Settings settings{};
  for (const auto& [name, binding] : bindings_)
    if (binding.settings != nullptr && *binding.settings == typeid(Settings)) binding.assign(&settings, *this, name);
  return settings;
}

template <auto member>
ParameterBuilder& ParameterBuilder::to() {
  using Member = detail::member_of<decltype(member)>;
  spec_.binding.settings = &typeid(typename Member::settings);
  spec_.binding.assign = [](void* settings, const Parameters& values, std::string_view name) {
    static_cast<typename Member::settings*>(settings)->*member = values.get<typename Member::value>(name);
  };
  return *this;
}

// Checks one component block against its declaration and appends every problem found (wrong types,
// out-of-range values, missing required keys, unknown keys with the closest valid names). Keys listed in
// `reserved` (such as "type") are accepted without a declaration. Returns the values with defaults filled.
Parameters validate_parameters(const ComponentDeclaration& declaration, const json& block,
                               const std::string& pointer, std::vector<Problem>& problems,
                               const std::vector<std::string>& reserved = {"type"});

// Escapes a key for use in a JSON pointer ("~" -> "~0", "/" -> "~1").
std::string pointer_escape(std::string_view key);

}  // namespace mtled
