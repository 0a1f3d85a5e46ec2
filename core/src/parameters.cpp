#include "mtled/parameters.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace mtled {

namespace {
std::string format_number(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format("{:g}", v);
}

std::string json_type_name(const json& v) {
  if (v.is_number_integer() || v.is_number_unsigned()) return "integer";
  if (v.is_number_float()) return "number";
  return v.type_name();
}

std::string short_value(const json& v) {
  std::string text = v.dump(-1, ' ', false, json::error_handler_t::replace);  // never throws on bad UTF-8
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}
}  // namespace

std::string_view to_string(Category category) {
  for (const CategoryInfo& info : kPluginCategories)
    if (info.category == category) return info.name;
  return category == Category::scene ? "scene" : "unknown";
}

std::optional<Category> category_from_string(std::string_view text) {
  if (text == "scene") return Category::scene;
  const Category category = category_from_literal(text);
  return category == Category::scene ? std::nullopt : std::optional(category);
}

const std::vector<Category>& plugin_categories() {
  static const std::vector<Category> categories = [] {
    std::vector<Category> all;
    for (const CategoryInfo& info : kPluginCategories) all.push_back(info.category);
    return all;
  }();
  return categories;
}

const CategoryInfo& category_info(Category category) {
  for (const CategoryInfo& info : kPluginCategories)
    if (info.category == category) return info;
  throw std::logic_error(fmt::format("category_info: {} is not a plugin category", to_string(category)));
}

std::string_view to_string(ParameterType type) {
  switch (type) {
    case ParameterType::number: return "number";
    case ParameterType::integer: return "integer";
    case ParameterType::boolean: return "boolean";
    case ParameterType::string: return "string";
    case ParameterType::vector3: return "vector3";
    case ParameterType::number_list: return "number_list";
    case ParameterType::string_list: return "string_list";
    case ParameterType::node_set: return "node_set";
    case ParameterType::file: return "file";
    case ParameterType::number_map:
      return "number_map";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------------- ranges

bool NumericRange::contains(double value) const {
  if (!std::isfinite(value)) return false;
  if (nonzero && value == 0.0) return false;
  if (min && (min_exclusive ? value <= *min : value < *min)) return false;
  if (max && (max_exclusive ? value >= *max : value > *max)) return false;
  return true;
}

std::string NumericRange::describe() const {
  std::string text;
  if (min && max) {
    text = fmt::format("{}{}, {}{}", min_exclusive ? "(" : "[", format_number(*min), format_number(*max),
                       max_exclusive ? ")" : "]");
  } else if (min) {
    text = fmt::format("{} {}", min_exclusive ? ">" : ">=", format_number(*min));
  } else if (max) {
    text = fmt::format("{} {}", max_exclusive ? "<" : "<=", format_number(*max));
  }
  if (nonzero) text += text.empty() ? "!= 0" : " and != 0";
  return text.empty() ? "any" : text;
}

// ------------------------------------------------------------------------------------------------ specs

json ParameterSpec::to_json() const {
  json j = {
      {"name", name},
      {"type", std::string(to_string(type))},
      {"required", required},
      {"unit", unit},
      {"range", type == ParameterType::number || type == ParameterType::integer || type == ParameterType::number_list ||
                        type == ParameterType::number_map || type == ParameterType::vector3
                    ? range.describe()
                    : std::string("any")},
      {"doc", doc}};
  j["default"] = default_value ? *default_value : json(nullptr);
  if (!choices.empty()) j["choices"] = choices;
  return j;
}

json ParameterSpec::to_json_schema() const {
  json s = json::object();
  auto add_bounds = [this](json& target) {
    if (range.min) target[range.min_exclusive ? "exclusiveMinimum" : "minimum"] = *range.min;
    if (range.max) target[range.max_exclusive ? "exclusiveMaximum" : "maximum"] = *range.max;
    if (range.nonzero) target["not"] = {{"const", 0}};
  };
  switch (type) {
    case ParameterType::number: s["type"] = "number"; add_bounds(s); break;
    case ParameterType::integer: s["type"] = "integer"; add_bounds(s); break;
    case ParameterType::boolean: s["type"] = "boolean"; break;
    case ParameterType::string:
    case ParameterType::file: s["type"] = "string"; break;
    case ParameterType::vector3:
      s = {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}};
      break;
    case ParameterType::number_list: {
      json item = {{"type", "number"}};
      add_bounds(item);
      s = {{"type", "array"}, {"items", item}};
      break;
    }
    case ParameterType::number_map: {
      json item = {{"type", "number"}};
      add_bounds(item);
      s = {{"type", "object"}, {"additionalProperties", item}};
      break;
    }
    case ParameterType::string_list: s = {{"type", "array"}, {"items", {{"type", "string"}}}}; break;
    case ParameterType::node_set:
      s = syntax.schema;
      break;
  }
  if (!choices.empty()) {
    if (type == ParameterType::string_list) {
      s["items"]["enum"] = choices;
    } else {
      s["enum"] = choices;
    }
  }
  std::string description = doc;
  if (!unit.empty() && unit != "1") description += " [" + unit + "]";
  s["description"] = description;
  if (default_value) s["default"] = *default_value;
  return s;
}

ParameterBuilder& ParameterBuilder::doc(std::string text) { spec_.doc = std::move(text); return *this; }
ParameterBuilder& ParameterBuilder::unit(std::string unit) { spec_.unit = std::move(unit); return *this; }
ParameterBuilder& ParameterBuilder::defaults(json value) {
  spec_.default_value = std::move(value);
  spec_.required = false;
  return *this;
}
ParameterBuilder& ParameterBuilder::optional() { spec_.required = false; return *this; }
ParameterBuilder& ParameterBuilder::positive() { return greater_than(0.0); }
ParameterBuilder& ParameterBuilder::non_negative() { return at_least(0.0); }
ParameterBuilder& ParameterBuilder::nonzero() { spec_.range.nonzero = true; return *this; }
ParameterBuilder& ParameterBuilder::at_least(double value) {
  spec_.range.min = value;
  spec_.range.min_exclusive = false;
  return *this;
}
ParameterBuilder& ParameterBuilder::greater_than(double value) {
  spec_.range.min = value;
  spec_.range.min_exclusive = true;
  return *this;
}
ParameterBuilder& ParameterBuilder::at_most(double value) {
  spec_.range.max = value;
  spec_.range.max_exclusive = false;
  return *this;
}
ParameterBuilder& ParameterBuilder::less_than(double value) {
  spec_.range.max = value;
  spec_.range.max_exclusive = true;
  return *this;
}
ParameterBuilder& ParameterBuilder::between(double low, double high) { return at_least(low).at_most(high); }
ParameterBuilder& ParameterBuilder::choices(std::vector<json> allowed) {
  spec_.choices = std::move(allowed);
  return *this;
}

ComponentDeclaration& ComponentDeclaration::summary(std::string text) {
  summary_ = std::move(text);
  return *this;
}

ComponentDeclaration& ComponentDeclaration::example(json block) {
  example_ = std::move(block);
  return *this;
}

ComponentDeclaration& ComponentDeclaration::add(ParameterSpec spec) {
  if (find(spec.name)) throw std::logic_error("parameter '" + spec.name + "' declared twice in " + name_);
  parameters_.push_back(std::move(spec));
  return *this;
}

ParameterBuilder ComponentDeclaration::add_new(std::string name, ParameterType type) {
  ParameterSpec spec;
  spec.name = std::move(name);
  spec.type = type;
  add(std::move(spec));
  return ParameterBuilder(parameters_.back());
}

ParameterBuilder ComponentDeclaration::number(std::string name) { return add_new(std::move(name), ParameterType::number); }
ParameterBuilder ComponentDeclaration::integer(std::string name) { return add_new(std::move(name), ParameterType::integer); }
ParameterBuilder ComponentDeclaration::boolean(std::string name) {
  return add_new(std::move(name), ParameterType::boolean).unit("1");
}
ParameterBuilder ComponentDeclaration::string(std::string name) {
  return add_new(std::move(name), ParameterType::string).unit("1");
}
ParameterBuilder ComponentDeclaration::vector3(std::string name) { return add_new(std::move(name), ParameterType::vector3); }
ParameterBuilder ComponentDeclaration::number_list(std::string name) {
  return add_new(std::move(name), ParameterType::number_list);
}
ParameterBuilder ComponentDeclaration::number_map(std::string name) {
  return add_new(std::move(name), ParameterType::number_map);
}
ParameterBuilder ComponentDeclaration::string_list(std::string name) {
  return add_new(std::move(name), ParameterType::string_list).unit("1");
}
ParameterBuilder ComponentDeclaration::node_set(std::string name, ValueSyntax syntax) {
  ParameterBuilder builder = add_new(std::move(name), ParameterType::node_set).unit("1");
  parameters_.back().syntax = std::move(syntax);
  return builder;
}
ParameterBuilder ComponentDeclaration::file(std::string name) {
  return add_new(std::move(name), ParameterType::file).unit("1");
}

const ParameterSpec* ComponentDeclaration::find(std::string_view name) const {
  for (const auto& p : parameters_)
    if (p.name == name) return &p;
  return nullptr;
}

json ComponentDeclaration::to_json() const {
  json params = json::array();
  for (const auto& p : parameters_) params.push_back(p.to_json());
  return {{"name", name_}, {"category", std::string(to_string(category_))}, {"summary", summary_},
          {"parameters", params}, {"example", example_}};
}

json ComponentDeclaration::to_json_schema() const {
  json properties = {{"type", {{"const", name_}, {"description", summary_}}}};
  json required = json::array({"type"});
  for (const auto& p : parameters_) {
    properties[p.name] = p.to_json_schema();
    if (p.required) required.push_back(p.name);
  }
  return {{"type", "object"},
          {"title", std::string(to_string(category_)) + " " + name_},
          {"description", summary_},
          {"properties", properties},
          {"required", required},
          {"additionalProperties", false}};
}

// ------------------------------------------------------------------------------------------- parameters

Parameters::Parameters(const ComponentDeclaration& declaration, json values, std::string pointer)
    : component_(declaration.name()), pointer_(std::move(pointer)), values_(std::move(values)) {
  for (const auto& p : declaration.parameters()) {
    types_.emplace_back(p.name, p.type);
    if (p.binding.assign != nullptr) bindings_.emplace_back(p.name, p.binding);
  }
}

std::string Parameters::pointer(std::string_view name) const { return pointer_ + "/" + pointer_escape(name); }

bool Parameters::has(std::string_view name) const {
  const auto it = values_.find(std::string(name));
  return it != values_.end() && !it->is_null();
}

const json& Parameters::value(std::string_view name, ParameterType expected) const {
  for (const auto& [n, type] : types_) {
    if (n != name) continue;
    if (type != expected)
      throw std::logic_error(fmt::format("{}: parameter '{}' is a {}, read as {}", component_, name,
                                         to_string(type), to_string(expected)));
    const auto it = values_.find(std::string(name));
    if (it == values_.end() || it->is_null())
      throw std::logic_error(fmt::format("{}: optional parameter '{}' read without a check", component_, name));
    return *it;
  }
  throw std::logic_error(fmt::format("{}: parameter '{}' is not declared", component_, name));
}

double Parameters::number(std::string_view name) const { return value(name, ParameterType::number).get<double>(); }
long Parameters::integer(std::string_view name) const { return value(name, ParameterType::integer).get<long>(); }
bool Parameters::boolean(std::string_view name) const { return value(name, ParameterType::boolean).get<bool>(); }
std::string Parameters::string(std::string_view name) const {
  return value(name, ParameterType::string).get<std::string>();
}
Vec3 Parameters::vector3(std::string_view name) const {
  const auto& v = value(name, ParameterType::vector3);
  return Vec3(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
}
std::vector<double> Parameters::number_list(std::string_view name) const {
  return value(name, ParameterType::number_list).get<std::vector<double>>();
}
std::map<std::string, double> Parameters::number_map(std::string_view name) const {
  return value(name, ParameterType::number_map).get<std::map<std::string, double>>();
}
std::vector<std::string> Parameters::string_list(std::string_view name) const {
  return value(name, ParameterType::string_list).get<std::vector<std::string>>();
}
std::filesystem::path Parameters::file(std::string_view name) const {
  return std::filesystem::path(value(name, ParameterType::file).get<std::string>());
}

std::string pointer_escape(std::string_view key) {
  std::string out;
  for (char c : key) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

// ------------------------------------------------------------------------------------------- validation

namespace {

std::string with_unit(const ParameterSpec& spec) {
  return (spec.unit.empty() || spec.unit == "1") ? "" : " " + spec.unit;
}

std::string range_message(const ParameterSpec& spec, const std::string& value_text) {
  return fmt::format("{} is out of range: allowed {}{} ({})", value_text, spec.range.describe(), with_unit(spec),
                     spec.doc);
}

std::string choices_text(const std::vector<json>& choices) {
  std::string text;
  for (const auto& c : choices) text += (text.empty() ? "" : ", ") + c.dump();
  return text;
}

bool check_choice(const ParameterSpec& spec, const json& v, const std::string& where, std::vector<Problem>& problems) {
  if (spec.choices.empty()) return true;
  for (const auto& c : spec.choices)
    if (c == v) return true;
  std::string message = fmt::format("{} is not one of {}", v.dump(), choices_text(spec.choices));
  if (v.is_string()) {
    std::vector<std::string> names;
    for (const auto& c : spec.choices)
      if (c.is_string()) names.push_back(c.get<std::string>());
    const auto hint = did_you_mean(v.get<std::string>(), names);
    if (!hint.empty()) message += "; " + hint;
  }
  problems.push_back({where, message});
  return false;
}

bool is_number(const json& v) { return v.is_number() && std::isfinite(v.get<double>()); }

// One entry of a list or map of numbers: a finite number in the spec's range, named by its own pointer.
bool check_number_entry(const ParameterSpec& spec, const json& entry, const std::string& at,
                        std::vector<Problem>& problems) {
  if (!is_number(entry)) {
    problems.push_back({at, fmt::format("expected a number{}, got {} {}", with_unit(spec), json_type_name(entry),
                                        short_value(entry))});
    return false;
  }
  if (!spec.range.contains(entry.get<double>())) {
    problems.push_back({at, range_message(spec, format_number(entry.get<double>()))});
    return false;
  }
  return true;
}

// Each entry of a list of numbers, or of an object of named numbers (every bad entry named).
bool check_number_list(const ParameterSpec& spec, const json& v, const std::string& where,
                       std::vector<Problem>& problems) {
  bool ok = true;
  for (std::size_t i = 0; i < v.size(); ++i)
    ok = check_number_entry(spec, v[i], where + "/" + std::to_string(i), problems) && ok;
  return ok;
}
bool check_number_map(const ParameterSpec& spec, const json& v, const std::string& where,
                      std::vector<Problem>& problems) {
  bool ok = true;
  for (const auto& [key, entry] : v.items())
    ok = check_number_entry(spec, entry, where + "/" + pointer_escape(key), problems) && ok;
  return ok;
}

// Each entry of a list of strings: a string among the spec's choices, if it has any (every bad entry named).
bool check_string_list(const ParameterSpec& spec, const json& v, const std::string& where,
                       std::vector<Problem>& problems) {
  bool ok = true;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::string at = where + "/" + std::to_string(i);
    if (!v[i].is_string()) {
      problems.push_back({at, fmt::format("expected a string, got {} {}", json_type_name(v[i]), short_value(v[i]))});
      ok = false;
    } else {
      ok = check_choice(spec, v[i], at, problems) && ok;
    }
  }
  return ok;
}

// Checks one value against its spec; returns false (with problems) if unusable.
bool check_value(const ParameterSpec& spec, const json& v, const std::string& where, std::vector<Problem>& problems) {
  const auto wrong_type = [&](const std::string& expected) {
    problems.push_back({where, fmt::format("expected {}, got {} {} ({})", expected, json_type_name(v), short_value(v),
                                           spec.doc)});
    return false;
  };
  switch (spec.type) {
    case ParameterType::number:
      if (!is_number(v)) return wrong_type("a number" + with_unit(spec));
      if (!spec.range.contains(v.get<double>())) {
        problems.push_back({where, range_message(spec, format_number(v.get<double>()))});
        return false;
      }
      return true;
    case ParameterType::integer:
      if (!(v.is_number_integer() || v.is_number_unsigned()) &&
          !(v.is_number_float() && std::nearbyint(v.get<double>()) == v.get<double>() &&
            std::abs(v.get<double>()) < 1e15))
        return wrong_type("an integer");
      if (!spec.range.contains(v.get<double>())) {
        problems.push_back({where, range_message(spec, format_number(v.get<double>()))});
        return false;
      }
      // Read back as a long: 18446744073709551615 would wrap to -1 past an "at least 1" range.
      if (std::abs(v.get<double>()) >= 1e15) {
        problems.push_back({where, fmt::format("{} is too large for an integer parameter (at most 1e15 in "
                                               "magnitude; {})", short_value(v), spec.doc)});
        return false;
      }
      return check_choice(spec, json(v.get<long>()), where, problems);
    case ParameterType::boolean:
      if (!v.is_boolean()) return wrong_type("true or false");
      return true;
    case ParameterType::string:
      if (!v.is_string()) return wrong_type("a string");
      return check_choice(spec, v, where, problems);
    case ParameterType::file:
      if (!v.is_string() || v.get<std::string>().empty()) return wrong_type("a file path");
      return true;
    case ParameterType::vector3: {
      if (!v.is_array() || v.size() != 3 || !is_number(v[0]) || !is_number(v[1]) || !is_number(v[2]))
        return wrong_type("3 numbers [x, y, z]" + with_unit(spec));
      const double norm = std::hypot(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
      if (spec.range.nonzero && norm == 0.0) {
        problems.push_back({where, fmt::format("must not be the zero vector ({})", spec.doc)});
        return false;
      }
      return true;
    }
    case ParameterType::number_list:
      if (!v.is_array()) return wrong_type("a list of numbers" + with_unit(spec));
      return check_number_list(spec, v, where, problems);
    case ParameterType::number_map:
      if (!v.is_object()) return wrong_type("an object of named numbers {\"name\": value}" + with_unit(spec));
      return check_number_map(spec, v, where, problems);
    case ParameterType::string_list:
      if (!v.is_array()) return wrong_type("a list of strings");
      return check_string_list(spec, v, where, problems);
    case ParameterType::node_set:
      return spec.syntax.check(v, where, problems);
  }
  return false;
}

}  // namespace

Parameters validate_parameters(const ComponentDeclaration& declaration, const json& block, const std::string& pointer,
                               std::vector<Problem>& problems, const std::vector<std::string>& reserved) {
  json values = json::object();
  if (!block.is_object()) {
    problems.push_back({pointer, fmt::format("expected an object with the parameters of {} \"{}\", got {}",
                                             to_string(declaration.category()), declaration.name(),
                                             json_type_name(block))});
    return Parameters(declaration, values, pointer);
  }
  std::vector<std::string> known = reserved;
  for (const auto& spec : declaration.parameters()) known.push_back(spec.name);

  for (const auto& [key, v] : block.items()) {
    bool is_known = false;
    for (const auto& k : known) is_known = is_known || (k == key);
    if (!is_known) {
      std::string message = fmt::format("unknown key \"{}\" for {} \"{}\"", key, to_string(declaration.category()),
                                        declaration.name());
      const auto hint = did_you_mean(key, known);
      if (!hint.empty()) {
        message += "; " + hint;
      } else {
        message += fmt::format(" (see `mtled plugins --describe {}`)", declaration.name());
      }
      problems.push_back({pointer + "/" + pointer_escape(key), message});
    }
  }
  for (const auto& spec : declaration.parameters()) {
    const std::string where = pointer + "/" + pointer_escape(spec.name);
    const auto it = block.find(spec.name);
    if (it == block.end() || it->is_null()) {
      if (spec.default_value) {
        values[spec.name] = *spec.default_value;
      } else if (spec.required) {
        problems.push_back({where, fmt::format("required {} parameter \"{}\" is missing: {}{}",
                                               declaration.name(), spec.name, spec.doc,
                                               spec.range.unbounded() ? "" : " (allowed " + spec.range.describe() +
                                                                                 with_unit(spec) + ")")});
      }
      continue;
    }
    if (check_value(spec, *it, where, problems)) values[spec.name] = *it;
  }
  return Parameters(declaration, std::move(values), pointer);
}

}  // namespace mtled
