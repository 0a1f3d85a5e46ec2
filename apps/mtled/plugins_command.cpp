// mtled plugins / validate / schema: everything that reads declarations without running anything.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <iostream>

#include "commands.hpp"
#include "mtled/log.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/scene.hpp"

namespace mtled::app {

namespace {

struct Listed {
  PluginCatalog::Available available;
  const ComponentDeclaration* declaration = nullptr;
  std::string error;
};

std::vector<Listed> load_all(PluginCatalog& catalog) {
  std::vector<Listed> list;
  for (const auto& a : catalog.available()) {
    Listed item{a, nullptr, ""};
    try {
      item.declaration = &catalog.load(a.category, a.name);
    } catch (const InputError& e) {
      item.error = e.what();
      log().warn("{}", item.error);
    }
    list.push_back(std::move(item));
  }
  for (const auto& d : catalog.duplicates()) log().warn("{}", d.format());
  return list;
}

std::string markdown_cell(std::string text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string default_text(const ParameterSpec& p) {
  if (p.default_value) return "`" + p.default_value->dump() + "`";
  return p.required ? "required" : "optional";
}

void describe_markdown(std::ostream& out, const ComponentDeclaration& d, const std::string& heading) {
  out << heading << " `" << d.name() << "`\n\n" << d.summary() << "\n\n";
  if (d.parameters().empty()) {
    out << "No parameters.\n\n";
    return;
  }
  out << "| parameter | type | default | unit | allowed | description |\n| --- | --- | --- | --- | --- | --- |\n";
  for (const auto& p : d.parameters()) {
    std::string allowed = p.to_json()["range"].get<std::string>();
    if (!p.choices.empty()) {
      std::vector<std::string> c;
      for (const auto& v : p.choices) c.push_back(v.dump());
      allowed = fmt::format("{}", fmt::join(c, ", "));
    }
    out << fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", p.name, to_string(p.type), markdown_cell(default_text(p)),
                       p.unit, markdown_cell(allowed), markdown_cell(p.doc));
  }
  out << "\n";
}

}  // namespace

// Where a component goes in a scene, with its declaration's example parameters: the block to paste.
std::string example_scene_block(const ComponentDeclaration& d) {
  nlohmann::ordered_json block = {{"type", d.name()}};
  if (d.example().is_object())
    for (const auto& [key, value] : d.example().items()) block[key] = value;
  const std::string text = block.dump();
  if (d.category() == Category::scene) return text;
  const CategoryInfo& info = category_info(d.category());
  if (info.blocks == SceneBlocks::none) return text;
  const bool list = info.blocks == SceneBlocks::list || info.blocks == SceneBlocks::non_empty_list;
  if (list) return fmt::format("\"{}\": [{}]", info.scene_key, text);
  return fmt::format("\"{}\": {}", info.scene_key, text);
}

int list_plugins(const std::vector<std::filesystem::path>& plugin_paths, bool as_json, bool as_markdown,
                 const std::string& describe) {
  PluginCatalog catalog(plugin_search_path(plugin_paths, {}));
  if (!describe.empty()) {
    std::string category_name, name = describe;
    if (const auto slash = describe.find('/'); slash != std::string::npos) {
      category_name = describe.substr(0, slash);
      name = describe.substr(slash + 1);
    }
    std::vector<const PluginCatalog::Available*> matches;
    std::vector<std::string> all_names;
    for (const auto& a : catalog.available()) {
      all_names.push_back(a.name);
      if (a.name == name && (category_name.empty() || to_string(a.category) == category_name)) matches.push_back(&a);
    }
    if (matches.empty()) {
      const auto hint = did_you_mean(name, all_names);
      throw InputError("--describe " + describe, fmt::format("no component of that name{}", hint.empty() ? "" : "; " + hint));
    }
    if (matches.size() > 1)
      throw InputError("--describe " + describe, "several categories have a component of that name: give CATEGORY/NAME");
    const auto& declaration = catalog.load(matches.front()->category, matches.front()->name);
    if (as_json) {
      json j = declaration.to_json();
      j["library"] = matches.front()->file.string();
      std::cout << j.dump(2) << "\n";
    } else {
      describe_markdown(std::cout, declaration, fmt::format("{} {}", to_string(declaration.category()), "component"));
      std::cout << "example, in a scene:\n\n    " << example_scene_block(declaration) << "\n\n";
      std::cout << "library: " << matches.front()->file.string() << "\n";
    }
    return 0;
  }

  const auto listed = load_all(catalog);
  if (as_json) {
    json list = json::array();
    for (const auto& item : listed) {
      json j = item.declaration != nullptr ? item.declaration->to_json()
                                           : json{{"name", item.available.name},
                                                  {"category", std::string(to_string(item.available.category))},
                                                  {"parameters", json::array()},
                                                  {"error", item.error}};
      j["library"] = item.available.file.string();
      list.push_back(j);
    }
    std::cout << list.dump(2) << "\n";
  } else if (as_markdown) {
    std::cout << "# Parameter reference\n\n"
              << "Generated by `mtled plugins --markdown` from each component's declaration; do not edit by hand "
                 "(a test checks that it is current).\n\n";
    std::cout << "## Scene sections of the kernel\n\n";
    describe_markdown(std::cout, discretisation_declaration(), "###");
    for (const auto& section : run_scene_sections()) describe_markdown(std::cout, *section.declaration, "###");
    for (Category category : plugin_categories()) {
      std::cout << "## " << to_string(category) << "\n\n";
      for (const auto& item : listed)
        if (item.available.category == category && item.declaration != nullptr)
          describe_markdown(std::cout, *item.declaration, "###");
    }
  } else {
    for (Category category : plugin_categories()) {
      std::cout << to_string(category) << ":\n";
      for (const auto& item : listed) {
        if (item.available.category != category) continue;
        std::cout << fmt::format("  {:<24} {}\n", item.available.name,
                                 item.declaration != nullptr ? item.declaration->summary() : "REFUSED: " + item.error);
      }
    }
  }
  return 0;
}

int print_schema(const std::vector<std::filesystem::path>& plugin_paths) {
  PluginCatalog catalog(plugin_search_path(plugin_paths, {}));
  std::cout << scene_json_schema(catalog, run_scene_sections()).dump(2) << "\n";
  return 0;
}

int validate_scene_command(const SceneOptions& options) {
  SceneDocument document = read_scene(options.scene, options.overrides);
  PluginCatalog catalog(plugin_search_path(options.plugin_paths, scene_plugin_paths(document)));
  const Scene scene = validate_scene(std::move(document), catalog, run_scene_sections());
  std::cout << fmt::format("{}: valid; plugins it uses: {}\n", options.scene.string(),
                           fmt::join(catalog.loaded_files(), ", "));
  return 0;
}

}  // namespace mtled::app
