#include "mtled/scene.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <optional>
#include <sstream>

namespace fs = std::filesystem;

namespace mtled {

namespace {

// Records the line of every value of an already syntax-checked JSON text, keyed by JSON pointer.
class LineScanner {
 public:
  LineScanner(const std::string& text, std::map<std::string, int>& lines) : text_(text), lines_(lines) {}
  void scan() {
    skip();
    value("");
  }

 private:
  void skip() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  std::string string_token() {
    std::string out;
    ++pos_;  // opening quote
    while (pos_ < text_.size() && text_[pos_] != '"') {
      if (text_[pos_] == '\\' && pos_ + 1 < text_.size()) {
        ++pos_;
        switch (text_[pos_]) {
          case 'n': out += '\n'; break;
          case 't': out += '\t'; break;
          case 'u': out += '?'; pos_ += 4; break;  // keys with \u escapes are not worth exact lines
          default: out += text_[pos_];
        }
      } else {
        out += text_[pos_];
      }
      ++pos_;
    }
    ++pos_;  // closing quote
    return out;
  }
  void value(const std::string& pointer) {
    skip();
    if (pos_ >= text_.size()) return;
    lines_.emplace(pointer, line_);
    const char c = text_[pos_];
    if (c == '{') {
      ++pos_;
      skip();
      while (pos_ < text_.size() && text_[pos_] != '}') {
        const int key_line = line_;
        const std::string key = string_token();
        skip();
        ++pos_;  // ':'
        const std::string child = pointer + "/" + pointer_escape(key);
        value(child);
        lines_[child] = key_line;  // the key's line reads best in messages
        skip();
        if (pos_ < text_.size() && text_[pos_] == ',') ++pos_;
        skip();
      }
      ++pos_;
    } else if (c == '[') {
      ++pos_;
      skip();
      for (int i = 0; pos_ < text_.size() && text_[pos_] != ']'; ++i) {
        value(pointer + "/" + std::to_string(i));
        skip();
        if (pos_ < text_.size() && text_[pos_] == ',') ++pos_;
        skip();
      }
      ++pos_;
    } else if (c == '"') {
      string_token();
    } else {
      while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_])) && text_[pos_] != ',' &&
             text_[pos_] != '}' && text_[pos_] != ']')
        ++pos_;
    }
  }

  const std::string& text_;
  std::map<std::string, int>& lines_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

std::string json_type(const json& v) { return v.is_number_integer() ? "integer" : v.type_name(); }

// A scene nests a few levels. LineScanner, and nlohmann's dump() in messages, recurse once per level: a
// text nested many thousands deep (which json::parse itself accepts) would overflow the stack.
constexpr int kMaxNesting = 100;

// The offset of the first '[' or '{' of syntactically valid JSON `text` nested deeper than kMaxNesting.
std::optional<std::size_t> too_deep(const std::string& text) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxNesting) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return std::nullopt;
}

// "name:line:column" of the character at `offset` (1-based line and column).
std::string text_location(const std::string& name, const std::string& text, std::size_t offset) {
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n');
  const std::size_t line_start = text.rfind('\n', offset);
  const std::size_t column = offset - (line_start == std::string::npos ? 0 : line_start + 1) + 1;
  return fmt::format("{}:{}:{}", name, line, column);
}

// json::parse throws out_of_range (not parse_error) for a number beyond a double's range, such as 1e400; its
// message quotes the number. Found by tests/fuzz: it escaped as "error: [json.exception.out_of_range.406]".
std::string number_overflow_message(const json::out_of_range& e, std::string& literal) {
  const std::string message = e.what();
  const auto open = message.find('\''), close = message.rfind('\'');
  if (open != std::string::npos && close > open) literal = message.substr(open + 1, close - open - 1);
  return fmt::format("the number {} is too large: numbers must lie within +-1.8e308 (a mistyped exponent?)",
                     literal.empty() ? std::string("here") : literal);
}

std::string too_deep_message() {
  return fmt::format("lists and objects nested more than {} deep: a scene needs a few levels; is this a scene file?",
                     kMaxNesting);
}

}  // namespace

fs::path SceneDocument::directory() const { return file.empty() ? fs::current_path() : file.parent_path(); }

std::string SceneDocument::locate(const std::string& pointer) const {
  for (const auto& o : overrides)
    if (pointer == o || pointer.rfind(o + "/", 0) == 0) return "--set " + pointer;
  std::string p = pointer;
  while (true) {
    const auto it = lines.find(p);
    if (it != lines.end()) return fmt::format("{}:{}: {}", name, it->second, pointer.empty() ? "/" : pointer);
    if (p.empty()) break;
    p = p.substr(0, p.rfind('/'));
  }
  return fmt::format("{}: {}", name, pointer);
}

SceneDocument parse_scene(const std::string& text, const std::string& name, const std::vector<std::string>& overrides) {
  SceneDocument document;
  document.name = name;
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw InputError(name, "the scene file is empty: a scene is a JSON object { \"mesh\": ..., ... } (see share/scenes)");
  try {
    document.root = json::parse(text);
  } catch (const json::parse_error& e) {
    // nlohmann's message: "[json.exception.parse_error.101] parse error at line L, column C: <what>"; the line
    // and column are recomputed from the byte offset (1-based, the offending character).
    std::string message = e.what();
    const auto colon = message.find(": ", message.find("parse error"));
    if (colon != std::string::npos) message = message.substr(colon + 2);
    const std::size_t offset = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    const std::size_t line_start = text.rfind('\n', offset == 0 ? 0 : offset - 1);
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n');
    const std::size_t column = offset - (line_start == std::string::npos || offset == 0 ? 0 : line_start + 1) + 1;
    const std::string where = fmt::format("{}:{}:{}", name, line, column);
    // The parser read past the last character: the text stopped before the JSON did.
    const bool past_end = e.byte > text.size() || message.find("unexpected end of input") != std::string::npos;
    std::string hint = "check for a missing comma, quote or bracket";
    if (past_end)
      hint = "the file ends early: is it truncated, or is a closing '}' or ']' missing?";
    throw InputError(where, fmt::format("invalid JSON: {} ({})", message, hint));
  } catch (const json::out_of_range& e) {
    std::string literal;
    const std::string message = number_overflow_message(e, literal);
    const std::size_t at = literal.empty() ? std::string::npos : text.find(literal);
    throw InputError(at == std::string::npos ? name : text_location(name, text, at), message);
  }
  if (!document.root.is_object()) throw InputError(name, "a scene must be a JSON object { ... }");
  if (const auto offset = too_deep(text)) throw InputError(text_location(name, text, *offset), too_deep_message());
  LineScanner(text, document.lines).scan();
  for (const auto& o : overrides) apply_override(document, o);
  return document;
}

SceneDocument read_scene(const fs::path& file, const std::vector<std::string>& overrides) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot read the scene file (does it exist, and is it readable?)");
  std::stringstream buffer;
  buffer << in.rdbuf();
  SceneDocument document = parse_scene(buffer.str(), file.filename().string(), overrides);
  document.file = fs::absolute(file);
  return document;
}

void apply_override(SceneDocument& document, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (assignment.empty() || assignment[0] != '/' || eq == std::string::npos)
    throw InputError("--set " + assignment,
                     "expected /json/pointer=value, for example --set /needle/depth=0.005");
  const std::string pointer = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  // Scene files are checked for UTF-8 by the parser; an override's bare words are not, and a string that is
  // not UTF-8 made every later dump() (messages, summary.json) throw. Found by tests/fuzz.
  try {
    (void)json(assignment).dump();
  } catch (const json::type_error&) {
    const std::string shown = json(pointer).dump(-1, ' ', false, json::error_handler_t::replace);
    throw InputError("--set " + shown.substr(1, shown.size() - 2),
                     "the override is not valid UTF-8 text: check the shell's encoding");
  }
  json value;
  try {
    value = json::parse(text);
    if (too_deep(text)) throw InputError("--set " + pointer, too_deep_message());
  } catch (const json::parse_error&) {
    value = text;  // bare words are strings: --set /shape_function/type=mls
  } catch (const json::out_of_range& e) {
    std::string literal;
    throw InputError("--set " + pointer, number_overflow_message(e, literal));
  }
  try {
    // Missing objects on the way are created (optional sections such as /discretisation); a misspelt key
    // is then reported by validation like any other unknown key. Lists are not grown: indices must exist.
    const json::json_pointer target(pointer);
    std::vector<std::string> tokens;
    for (json::json_pointer p = target; !p.empty(); p = p.parent_pointer()) tokens.insert(tokens.begin(), p.back());
    const json* node = &document.root;
    std::size_t depth = 0;  // tokens that exist
    for (const auto& token : tokens) {
      if (node->is_array()) {
        // from_chars, not stoul: an index too large for std::size_t is out of range like any other.
        std::size_t at = 0;
        const bool index = !token.empty() && token.find_first_not_of("0123456789") == std::string::npos &&
                           std::from_chars(token.data(), token.data() + token.size(), at).ec == std::errc();
        if (!index || at >= node->size())
          throw InputError("--set " + pointer, fmt::format("\"{}\" is not an index of a list of {} entries", token,
                                                           node->size()));
        node = &(*node)[at];
      } else if (node->is_object() && node->contains(token)) {
        node = &(*node)[token];
      } else {
        break;
      }
      ++depth;
    }
    // Below the first missing key, nlohmann would make a list for a numeric token and grow it to the index
    // (an index of 10^19 threw std::length_error, found by tests/fuzz; 10^9 would take all the memory).
    for (std::size_t k = depth + 1; k < tokens.size(); ++k)
      if (!tokens[k].empty() && (tokens[k] == "-" || tokens[k].find_first_not_of("0123456789") == std::string::npos))
        throw InputError("--set " + pointer,
                         fmt::format("\"{}\" does not exist, so \"{}\" below it cannot be a list index: --set creates "
                                     "missing objects, not lists; set the whole list instead",
                                     tokens[depth], tokens[k]));
    document.root[target] = value;
  } catch (const json::exception& e) {
    throw InputError("--set " + pointer, fmt::format("cannot set this pointer: {}", e.what()));
  }
  document.overrides.push_back(pointer);
}

std::vector<fs::path> scene_plugin_paths(const SceneDocument& document) {
  std::vector<fs::path> paths;
  const auto it = document.root.find("plugin_paths");
  if (it == document.root.end() || !it->is_array()) return paths;
  for (const auto& p : *it) {
    if (!p.is_string()) continue;
    fs::path path(p.get<std::string>());
    paths.push_back((path.is_absolute() ? path : document.directory() / path).lexically_normal());
  }
  return paths;
}

const ComponentDeclaration& discretisation_declaration() {
  static const ComponentDeclaration declaration = [] {
    ComponentDeclaration d("discretisation", Category::scene);
    d.summary("How the mesh becomes a meshless model: integration points per background tet, consistent integration.");
    d.integer("integration_points_per_tet")
        .defaults(1)
        .choices({1, 4})
        .unit("1")
        .doc(
            "integration points in each background tet: 1 at the centroid (the paper's choice) or a 4-point "
            "rule exact for quadratics")
        .to<&DiscretisationSettings::integration_points_per_tet>();
    d.boolean("consistent_integration")
        .defaults(true)
        .doc(
            "correct the test-function gradients so that the discrete equations reproduce homogeneous "
            "deformations exactly (variationally consistent integration, Chen et al. 2013; passes the patch "
            "test); false gives the paper's plain MTLED quadrature")
        .to<&DiscretisationSettings::consistent_integration>();
    d.string("precision")
        .defaults("single")
        .choices({"double", "single"})
        .doc(
            "the precision the force kernel stores its rows in: single stores the shape-function gradients and "
            "the corrected test gradients as float (about 6e-8 relative rounding each; 11-28% faster on the shipped "
            "needle scenes, fields "
            "within 1e-8 of double's); double stores the gradients alone and corrects them in the kernel, the "
            "reference for round-off checks. Stresses, sums and the state are double in both "
            "(docs/performance.md)")
        .to<&DiscretisationSettings::precision>();
    return d;
  }();
  return declaration;
}

namespace {

struct Validator {
  PluginCatalog& catalog;
  fs::path scene_directory;
  std::vector<Problem> problems;

  // A file parameter's relative path is taken from the scene's folder (in components and sections alike); the file
  // must exist.
  json with_files_resolved(const ComponentDeclaration& declaration, const json& block, const std::string& pointer) {
    json resolved = block;
    for (const auto& spec : declaration.parameters()) {
      if (spec.type != ParameterType::file) continue;
      const auto it = resolved.find(spec.name);
      if (it == resolved.end() || !it->is_string() || it->get<std::string>().empty()) continue;
      fs::path path(it->get<std::string>());
      if (path.is_relative()) path = scene_directory / path;
      path = path.lexically_normal();
      std::error_code ec;
      if (!fs::is_regular_file(path, ec))
        problems.push_back({pointer + "/" + pointer_escape(spec.name),
                            fmt::format("no such file: {} (a relative path is taken from the scene's folder, {}; {})",
                                        path.string(), scene_directory.string(), spec.doc)});
      *it = path.string();
    }
    return resolved;
  }

  std::optional<ComponentBlock> component(const json& block, const std::string& pointer, Category category) {
    if (!block.is_object()) {
      problems.push_back({pointer, fmt::format("expected an object {{\"type\": \"<{} name>\", ...}}, got {}",
                                               to_string(category), json_type(block))});
      return std::nullopt;
    }
    const auto type = block.find("type");
    if (type == block.end() || !type->is_string()) {
      const auto names = catalog.names(category);
      problems.push_back({pointer + "/type", fmt::format("every {} needs a \"type\" naming its component (available: {})",
                                                         to_string(category), fmt::join(names, ", "))});
      return std::nullopt;
    }
    const std::string name = type->get<std::string>();
    const ComponentDeclaration* declaration = nullptr;
    try {
      declaration = &catalog.load(category, name, pointer + "/type");
    } catch (const InputError& e) {
      problems.insert(problems.end(), e.problems().begin(), e.problems().end());
      return std::nullopt;
    }
    Parameters parameters =
        validate_parameters(*declaration, with_files_resolved(*declaration, block, pointer), pointer, problems);
    return ComponentBlock{name, std::move(parameters)};
  }

  std::vector<ComponentBlock> component_list(const json& root, const std::string& key, Category category,
                                             bool required) {
    std::vector<ComponentBlock> list;
    const auto it = root.find(key);
    if (it == root.end()) {
      if (required)
        problems.push_back({"/" + key, fmt::format("missing \"{}\": a list of {} blocks", key, to_string(category))});
      return list;
    }
    if (!it->is_array() || (required && it->empty())) {
      problems.push_back({"/" + key, fmt::format("expected a {}list of {} blocks, got {}", required ? "non-empty " : "",
                                                 to_string(category), json_type(*it))});
      return list;
    }
    for (std::size_t i = 0; i < it->size(); ++i) {
      if (auto block = component((*it)[i], fmt::format("/{}/{}", key, i), category)) list.push_back(std::move(*block));
    }
    return list;
  }
};

const std::vector<std::string>& kernel_keys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> all = {"$schema", "description", "plugin_paths"};
    for (const CategoryInfo& info : kPluginCategories)
      if (info.blocks != SceneBlocks::none) all.emplace_back(info.scene_key);
    all.emplace_back("discretisation");
    return all;
  }();
  return keys;
}

std::vector<std::string> top_level_keys(const std::vector<SceneSection>& sections) {
  std::vector<std::string> keys = kernel_keys();
  for (const auto& section : sections) keys.push_back(section.key);
  return keys;
}

// A problem's `where` is a JSON pointer into the scene ("/materials/0/mu") or a file location
// ("/data/mesh.msh:12", absolute paths also start with '/'): a pointer starts with a key of the scene.
bool is_scene_pointer(const std::string& where, const SceneDocument& document) {
  if (where.empty() || where[0] != '/') return false;
  const std::string first = where.substr(1, where.find('/', 1) == std::string::npos ? std::string::npos
                                                                                    : where.find('/', 1) - 1);
  const auto& keys = kernel_keys();
  return document.root.contains(first) || std::find(keys.begin(), keys.end(), first) != keys.end();
}

}  // namespace

const Parameters& Scene::section(const std::string& key) const {
  const auto it = sections.find(key);
  if (it == sections.end())
    throw std::logic_error(fmt::format("the scene was validated without its \"{}\" section", key));
  return it->second;
}

Scene validate_scene(SceneDocument document, PluginCatalog& catalog, const std::vector<SceneSection>& sections) {
  Validator v{catalog, document.directory(), {}};
  const json& root = document.root;
  const std::vector<std::string> keys = top_level_keys(sections);
  for (const auto& [key, value] : root.items()) {
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    const auto hint = did_you_mean(key, keys);
    v.problems.push_back({"/" + pointer_escape(key),
                          fmt::format("unknown top-level key \"{}\"; {}", key,
                                      hint.empty() ? fmt::format("allowed: {}", fmt::join(keys, ", ")) : hint)});
  }
  if (root.contains("description") && !root["description"].is_string())
    v.problems.push_back({"/description", "expected a string"});
  if (root.contains("plugin_paths")) {
    const json& paths = root["plugin_paths"];
    if (!paths.is_array()) {
      v.problems.push_back({"/plugin_paths", "expected a list of folder names"});
    } else {
      for (std::size_t i = 0; i < paths.size(); ++i)
        if (!paths[i].is_string()) v.problems.push_back({fmt::format("/plugin_paths/{}", i), "expected a folder name"});
    }
  }
  for (const auto& duplicate : catalog.duplicates()) v.problems.push_back(duplicate);

  Scene scene;
  auto required = [&](const std::string& key, Category category) -> ComponentBlock {
    const auto it = root.find(key);
    if (it == root.end()) {
      v.problems.push_back({"/" + key, fmt::format("missing \"{}\" (available {} types: {})", key, to_string(category),
                                                   fmt::join(catalog.names(category), ", "))});
      return {};
    }
    return v.component(*it, "/" + key, category).value_or(ComponentBlock{});
  };
  scene.mesh = required("mesh", Category::mesh);
  scene.shape_function = required("shape_function", Category::shape_function);
  scene.materials = v.component_list(root, "materials", Category::material, true);
  scene.boundaries = v.component_list(root, "boundaries", Category::boundary, false);
  // An optional block given as null is left out (--set /volumetric=null turns a scene's treatment off).
  if (root.contains("needle") && !root["needle"].is_null())
    scene.needle = v.component(root["needle"], "/needle", Category::needle);
  scene.integrator = required("integrator", Category::integrator);
  if (root.contains("volumetric") && !root["volumetric"].is_null())
    scene.volumetric = v.component(root["volumetric"], "/volumetric", Category::volumetric);
  if (root.contains("backend") && !root["backend"].is_null())
    scene.backend = v.component(root["backend"], "/backend", Category::backend);
  json discretisation = root.value("discretisation", json::object());
  if (discretisation.is_object() && discretisation.contains("volumetric")) {  // where earlier scenes chose it
    v.problems.push_back({"/discretisation/volumetric",
                          "the volumetric treatment is a component now: write \"volumetric\": {\"type\": "
                          "\"nodal_average\"} at the top level of the scene (leave it out for each point's own J)"});
    discretisation.erase("volumetric");
  }
  const json empty = json::object();
  scene.discretisation = validate_parameters(
      discretisation_declaration(), v.with_files_resolved(discretisation_declaration(), discretisation, "/discretisation"),
      "/discretisation", v.problems, {});
  for (const auto& section : sections) {
    const std::string pointer = "/" + section.key;
    const json block = v.with_files_resolved(*section.declaration, root.value(section.key, empty), pointer);
    scene.sections[section.key] = validate_parameters(*section.declaration, block, pointer, v.problems, {});
  }

  // At most one material may omit "region" (it fills every region the others leave).
  int without_region = 0;
  for (std::size_t i = 0; i < scene.materials.size(); ++i)
    if (!scene.materials[i].parameters.has("region") && ++without_region == 2)
      v.problems.push_back({fmt::format("/materials/{}", i),
                            "two materials without \"region\": name the mesh region each one fills"});

  if (!v.problems.empty()) {
    for (auto& p : v.problems)
      if (is_scene_pointer(p.where, document)) p.where = document.locate(p.where);
    throw InputError(std::move(v.problems));
  }
  scene.document = std::move(document);
  return scene;
}

InputError locate_problems(const InputError& error, const SceneDocument& document) {
  std::vector<Problem> problems = error.problems();
  for (auto& p : problems)
    if (is_scene_pointer(p.where, document)) p.where = document.locate(p.where);
  return InputError(std::move(problems));
}

json scene_json_schema(PluginCatalog& catalog, const std::vector<SceneSection>& sections) {
  // A section is not a component: no "type", every key optional.
  auto section_schema = [](const ComponentDeclaration& declaration) {
    json schema = declaration.to_json_schema();
    schema["properties"].erase("type");
    schema["required"] = json::array();
    return schema;
  };
  auto one_of = [&](Category category) {
    json options = json::array();
    for (const auto& name : catalog.names(category)) {
      try {
        options.push_back(catalog.load(category, name).to_json_schema());
      } catch (const InputError&) {
        // A plugin that cannot be loaded is left out of the schema; `mtled plugins` reports it.
      }
    }
    return json{{"oneOf", options}};
  };
  auto optional = [](json schema) {
    schema["oneOf"].push_back({{"type", "null"}});
    return schema;
  };
  json properties = {{"$schema", {{"type", "string"}}},
                     {"description", {{"type", "string"}, {"description", "free text about the scene"}}},
                     {"plugin_paths",
                      {{"type", "array"},
                       {"items", {{"type", "string"}}},
                       {"description", "extra plugin folders, relative to the scene"}}},
                     {"discretisation", section_schema(discretisation_declaration())}};
  json required = json::array();
  for (const CategoryInfo& info : kPluginCategories) {
    if (info.blocks == SceneBlocks::none) continue;
    json& schema = properties[std::string(info.scene_key)];
    switch (info.blocks) {
      case SceneBlocks::one:
        schema = one_of(info.category);
        break;
      case SceneBlocks::optional_one:
        schema = optional(one_of(info.category));
        break;
      case SceneBlocks::list:
        schema = {{"type", "array"}, {"items", one_of(info.category)}};
        break;
      case SceneBlocks::non_empty_list:
        schema = {{"type", "array"}, {"minItems", 1}, {"items", one_of(info.category)}};
        break;
      case SceneBlocks::none:
        break;
    }
    if (info.blocks == SceneBlocks::one || info.blocks == SceneBlocks::non_empty_list)
      required.push_back(info.scene_key);
  }
  for (const auto& section : sections) properties[section.key] = section_schema(*section.declaration);
  return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
          {"$id", "https://mtled.org/schema/scene.json"},
          {"title", "mtled scene"},
          {"type", "object"},
          {"properties", properties},
          {"required", required},
          {"additionalProperties", false}};
}

}  // namespace mtled
