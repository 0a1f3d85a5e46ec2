#include "mtled/node_selector.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

namespace mtled {

namespace {
using json = nlohmann::json;

const std::vector<std::string> kShapes = {"group", "plane", "box", "cylinder", "sphere"};
const std::vector<std::string> kOptions = {"tolerance", "surface_only"};

std::optional<Vec3> read_vec3(const json& parent, const std::string& key, const std::string& pointer,
                              std::vector<Problem>& problems, bool nonzero = false) {
  const std::string where = pointer + "/" + key;
  const auto it = parent.find(key);
  if (it == parent.end()) {
    problems.push_back({where, fmt::format("missing \"{}\" (3 numbers [x, y, z] in m)", key)});
    return std::nullopt;
  }
  const json& v = *it;
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
    problems.push_back({where, fmt::format("expected 3 numbers [x, y, z], got {}", v.dump())});
    return std::nullopt;
  }
  Vec3 x(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  if (!x.allFinite()) {
    problems.push_back({where, "coordinates must be finite"});
    return std::nullopt;
  }
  if (nonzero && x.norm() == 0.0) {
    problems.push_back({where, "must not be the zero vector"});
    return std::nullopt;
  }
  return x;
}

std::optional<double> read_positive(const json& parent, const std::string& key, const std::string& pointer,
                                    std::vector<Problem>& problems) {
  const std::string where = pointer + "/" + key;
  const auto it = parent.find(key);
  if (it == parent.end()) {
    problems.push_back({where, fmt::format("missing \"{}\" (a length > 0 in m)", key)});
    return std::nullopt;
  }
  if (!it->is_number() || !(it->get<double>() > 0.0) || !std::isfinite(it->get<double>())) {
    problems.push_back({where, fmt::format("expected a length > 0 m, got {}", it->dump())});
    return std::nullopt;
  }
  return it->get<double>();
}

bool only_keys(const json& object, const std::vector<std::string>& allowed, const std::string& pointer,
               std::vector<Problem>& problems) {
  bool ok = true;
  for (const auto& [key, value] : object.items()) {
    bool found = false;
    for (const auto& a : allowed) found = found || a == key;
    if (!found) {
      std::string message = fmt::format("unknown key \"{}\"", key);
      const auto hint = did_you_mean(key, allowed);
      message += hint.empty() ? fmt::format(" (allowed: {})", fmt::join(allowed, ", ")) : "; " + hint;
      problems.push_back({pointer + "/" + key, message});
      ok = false;
    }
  }
  return ok;
}
}  // namespace

namespace {
// The selector's one shape ("group", "plane", "box", "cylinder" or "sphere") into s.
void read_shape(const json& value, const std::string& pointer, NodeSelector& s, std::vector<Problem>& problems) {
  if (value.contains("group")) {
    s.kind = NodeSelector::Kind::group;
    if (!value["group"].is_string() || value["group"].get<std::string>().empty()) {
      problems.push_back({pointer + "/group", "expected the name of a node set or physical group of the mesh"});
    } else {
      s.group = value["group"].get<std::string>();
    }
  } else if (value.contains("plane")) {
    s.kind = NodeSelector::Kind::plane;
    const std::string p = pointer + "/plane";
    const json& o = value["plane"];
    if (!o.is_object()) {
      problems.push_back({p, "expected {\"point\": [x, y, z], \"normal\": [x, y, z]}"});
    } else {
      only_keys(o, {"point", "normal"}, p, problems);
      if (auto x = read_vec3(o, "point", p, problems)) s.point = *x;
      if (auto n = read_vec3(o, "normal", p, problems, true)) s.direction = n->normalized();
    }
  } else if (value.contains("box")) {
    s.kind = NodeSelector::Kind::box;
    const std::string p = pointer + "/box";
    const json& o = value["box"];
    if (!o.is_object()) {
      problems.push_back({p, "expected {\"min\": [x, y, z], \"max\": [x, y, z]}"});
    } else {
      only_keys(o, {"min", "max"}, p, problems);
      const auto lo = read_vec3(o, "min", p, problems);
      const auto hi = read_vec3(o, "max", p, problems);
      if (lo && hi) {
        s.min = *lo;
        s.max = *hi;
        if ((s.max.array() < s.min.array()).any())
          problems.push_back({p, "\"min\" must not exceed \"max\" in any coordinate"});
      }
    }
  } else if (value.contains("cylinder")) {
    s.kind = NodeSelector::Kind::cylinder;
    const std::string p = pointer + "/cylinder";
    const json& o = value["cylinder"];
    if (!o.is_object()) {
      problems.push_back({p, "expected {\"point\": [..], \"direction\": [..], \"radius\": r}"});
    } else {
      only_keys(o, {"point", "direction", "radius"}, p, problems);
      if (auto x = read_vec3(o, "point", p, problems)) s.point = *x;
      if (auto d = read_vec3(o, "direction", p, problems, true)) s.direction = d->normalized();
      if (auto r = read_positive(o, "radius", p, problems)) s.radius = *r;
    }
  } else {
    s.kind = NodeSelector::Kind::sphere;
    const std::string p = pointer + "/sphere";
    const json& o = value["sphere"];
    if (!o.is_object()) {
      problems.push_back({p, "expected {\"center\": [x, y, z], \"radius\": r}"});
    } else {
      only_keys(o, {"center", "radius"}, p, problems);
      if (auto x = read_vec3(o, "center", p, problems)) s.point = *x;
      if (auto r = read_positive(o, "radius", p, problems)) s.radius = *r;
    }
  }
}
}  // namespace

std::optional<NodeSelector> NodeSelector::parse(const json& value, const std::string& pointer,
                                                std::vector<Problem>& problems) {
  const std::size_t before = problems.size();
  if (!value.is_object()) {
    problems.push_back({pointer, fmt::format("expected a node selector object such as {{\"group\": \"bottom\"}} "
                                             "or {{\"plane\": {{\"point\": [..], \"normal\": [..]}}}}, got {}",
                                             value.dump())});
    return std::nullopt;
  }
  std::vector<std::string> allowed = kShapes;
  allowed.insert(allowed.end(), kOptions.begin(), kOptions.end());
  only_keys(value, allowed, pointer, problems);

  NodeSelector s;
  int shapes = 0;
  for (const auto& shape : kShapes) shapes += value.contains(shape) ? 1 : 0;
  if (shapes != 1) {
    problems.push_back({pointer, fmt::format("give exactly one of {} (found {})", fmt::join(kShapes, ", "), shapes)});
    return std::nullopt;
  }
  if (value.contains("tolerance")) {
    const auto& t = value["tolerance"];
    if (!t.is_number() || !(t.get<double>() >= 0.0)) {
      problems.push_back({pointer + "/tolerance", fmt::format("expected a length >= 0 m, got {}", t.dump())});
    } else {
      s.tolerance = t.get<double>();
    }
  }
  if (value.contains("surface_only")) {
    if (!value["surface_only"].is_boolean()) {
      problems.push_back({pointer + "/surface_only", "expected true or false"});
    } else {
      s.surface_only = value["surface_only"].get<bool>();
    }
  }
  read_shape(value, pointer, s, problems);
  if (problems.size() != before) return std::nullopt;
  return s;
}

bool NodeSelector::contains(const Vec3& x, double tol) const {
  switch (kind) {
    case Kind::group: return false;
    case Kind::plane: return std::abs(direction.dot(x - point)) <= tol;
    case Kind::box: return ((x.array() >= min.array() - tol) && (x.array() <= max.array() + tol)).all();
    case Kind::cylinder: {
      const Vec3 d = x - point;
      return (d - direction * direction.dot(d)).norm() <= radius + tol;
    }
    case Kind::sphere: return (x - point).norm() <= radius + tol;
  }
  return false;
}

std::string NodeSelector::describe() const {
  const auto v = [](const Vec3& x) { return fmt::format("[{:g}, {:g}, {:g}]", x[0], x[1], x[2]); };
  switch (kind) {
    case Kind::group: return fmt::format("group \"{}\"", group);
    case Kind::plane: return fmt::format("plane through {} with normal {}", v(point), v(direction));
    case Kind::box: return fmt::format("box {} to {}", v(min), v(max));
    case Kind::cylinder: return fmt::format("cylinder of radius {:g} m about {} along {}", radius, v(point), v(direction));
    case Kind::sphere: return fmt::format("sphere of radius {:g} m about {}", radius, v(point));
  }
  return "";
}

nlohmann::json NodeSelector::json_schema() {
  const json vec = {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}};
  const json length = {{"type", "number"}, {"exclusiveMinimum", 0}};
  auto shape = [&](const std::string& name, json inner) {
    json properties = {{name, std::move(inner)},
                       {"tolerance", {{"type", "number"}, {"minimum", 0}}},
                       {"surface_only", {{"type", "boolean"}}}};
    return json{{"type", "object"}, {"properties", properties}, {"required", {name}}, {"additionalProperties", false}};
  };
  auto object = [](json properties, json required) {
    return json{{"type", "object"}, {"properties", std::move(properties)}, {"required", std::move(required)},
                {"additionalProperties", false}};
  };
  return {{"description", "nodes chosen by mesh group or by geometry (reference coordinates, m)"},
          {"oneOf",
           {shape("group", {{"type", "string"}}),
            shape("plane", object({{"point", vec}, {"normal", vec}}, {"point", "normal"})),
            shape("box", object({{"min", vec}, {"max", vec}}, {"min", "max"})),
            shape("cylinder", object({{"point", vec}, {"direction", vec}, {"radius", length}},
                                     {"point", "direction", "radius"})),
            shape("sphere", object({{"center", vec}, {"radius", length}}, {"center", "radius"}))}}};
}

ValueSyntax NodeSelector::syntax() {
  return {[](const nlohmann::json& value, const std::string& where, std::vector<Problem>& problems) {
            return parse(value, where, problems).has_value();
          },
          json_schema()};
}

NodeSelector NodeSelector::from(const Parameters& parameters, std::string_view name) {
  std::vector<Problem> problems;
  auto selector = parse(parameters.values().at(std::string(name)), parameters.pointer(name), problems);
  if (!selector) throw InputError(std::move(problems));
  return *selector;
}

}  // namespace mtled
