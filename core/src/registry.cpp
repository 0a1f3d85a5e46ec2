#include "mtled/registry.hpp"

#include <fmt/format.h>

namespace mtled {

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
    ParameterBuilder(region).to<&MaterialRegion::region>();
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
    // Each name written once: a parameter is read through the member it fills (a node set by NodeSelector::from).
    if (p.binding.assign == nullptr && p.type != ParameterType::node_set)
      throw std::logic_error(fmt::format("{} \"{}\": parameter \"{}\" is bound to no member: end its declaration with "
                                         ".to<&Settings::member>() and read it with Parameters::read<Settings>()",
                                         to_string(expected), declaration.name(), p.name));
  }
}

void Registry::add_entry(ComponentDeclaration declaration, std::any factory) {
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
