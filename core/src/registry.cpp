#include "mtled/registry.hpp"

#include <fmt/format.h>

namespace mtled {

// Key functions: the interfaces' type information lives in libmtled_core only.
MeshSource::~MeshSource() = default;
ShapeFunctions::~ShapeFunctions() = default;
Material::~Material() = default;
Driver::~Driver() = default;
BoundaryCondition::~BoundaryCondition() = default;
NeedleModel::~NeedleModel() = default;
TimeIntegrator::~TimeIntegrator() = default;

std::string_view to_string(NeedlePhase phase) {
  return phase == NeedlePhase::penetration ? "penetration" : "indentation";
}

Vec3 NodalConstraints::total_reaction() const {
  Vec3 sum = Vec3::Zero();
  for (const auto& r : reactions) sum += r;
  return sum;
}

void NodalConstraints::set_components(const std::array<bool, 3>& components) {
  components_ = components;
  ++revision_;
}

void NodalConstraints::assign_nodes(std::vector<Index> nodes, const Vec3& value) {
  nodes_ = std::move(nodes);
  points_.clear();
  values.assign(nodes_.size(), value);
  ++revision_;
}

void NodalConstraints::add_node(Index node, const Vec3& value) {
  nodes_.push_back(node);
  values.push_back(value);
  ++revision_;
}

void NodalConstraints::add_point(const Vec3& point, const Vec3& value) {
  points_.push_back(point);
  values.push_back(value);
  ++revision_;
}

void NodalConstraints::keep_entries(const std::vector<char>& keep) {
  std::size_t kept = 0;
  for (std::size_t k = 0; k < keep.size(); ++k) {
    if (!keep[k]) continue;
    if (!nodes_.empty()) nodes_[kept] = nodes_[k];
    if (!points_.empty()) points_[kept] = points_[k];
    if (k < values.size()) values[kept] = values[k];
    if (k < reactions.size()) reactions[kept] = reactions[k];
    ++kept;
  }
  if (!nodes_.empty()) nodes_.resize(kept);
  if (!points_.empty()) points_.resize(kept);
  values.resize(std::min(values.size(), kept));
  reactions.resize(std::min(reactions.size(), kept));
  ++revision_;
}

void NodalConstraints::clear() {
  nodes_.clear();
  points_.clear();
  values.clear();
  ++revision_;
}

std::vector<ParameterSpec> common_parameters(Category category) {
  std::vector<ParameterSpec> specs;
  if (category == Category::material) {
    ParameterSpec region;
    region.name = "region";
    region.type = ParameterType::string;
    region.required = false;
    region.unit = "1";
    region.doc = "mesh region (physical volume group or ELSET) this material fills; omitted: every region "
                 "that no other material names";
    specs.push_back(region);
  }
  return specs;
}

Registry::Registry() = default;
Registry::~Registry() = default;

void Registry::check_category(const ComponentDeclaration& declaration, Category expected) {
  if (declaration.category() != expected)
    throw std::logic_error(fmt::format("component \"{}\" is declared as a {} but registered as a {}",
                                       declaration.name(), to_string(declaration.category()), to_string(expected)));
  for (const auto& p : declaration.parameters()) {
    if (p.doc.empty())
      throw std::logic_error(fmt::format("{} \"{}\": parameter \"{}\" has no doc", to_string(expected),
                                         declaration.name(), p.name));
    if (p.unit.empty())
      throw std::logic_error(fmt::format("{} \"{}\": parameter \"{}\" has no unit (use \"1\" if dimensionless)",
                                         to_string(expected), declaration.name(), p.name));
  }
}

void Registry::add_entry(ComponentDeclaration declaration, AnyFactory factory) {
  // The kernel's own per-category parameters join the component's declaration, so that validation, the
  // schema and the docs all see one list.
  ComponentDeclaration full = std::move(declaration);
  for (auto spec : common_parameters(full.category())) {
    if (full.find(spec.name))
      throw std::logic_error(fmt::format("{} \"{}\" declares \"{}\", which the kernel already provides",
                                         to_string(full.category()), full.name(), spec.name));
    full.add(std::move(spec));
  }
  auto key = std::make_pair(full.category(), full.name());
  if (entries_.count(key))
    throw std::logic_error(fmt::format("{} \"{}\" registered twice", to_string(full.category()), full.name()));
  entries_.emplace(std::move(key), Entry{std::move(full), std::move(factory)});
}

const ComponentDeclaration* Registry::find(Category category, std::string_view name) const {
  const auto it = entries_.find(std::make_pair(category, std::string(name)));
  return it == entries_.end() ? nullptr : &it->second.declaration;
}

std::vector<const ComponentDeclaration*> Registry::all() const {
  std::vector<const ComponentDeclaration*> list;
  for (const auto& [key, entry] : entries_) list.push_back(&entry.declaration);
  return list;
}

const Registry::Entry& Registry::entry(Category category, std::string_view name) const {
  const auto it = entries_.find(std::make_pair(category, std::string(name)));
  if (it == entries_.end())
    throw std::logic_error(fmt::format("{} \"{}\" is not registered", to_string(category), name));
  return it->second;
}

}  // namespace mtled
