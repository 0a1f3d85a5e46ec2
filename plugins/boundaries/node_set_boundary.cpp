#include "node_set_boundary.hpp"

#include <fmt/format.h>

#include "mtled/discretisation.hpp"
#include "mtled/log.hpp"

namespace mtled {

void NodeSetBoundary::declare_selection(ComponentDeclaration& d) {
  d.node_set("nodes", NodeSelector::syntax())
      .doc("the nodes this condition acts on: a mesh group or a geometric selector");
  d.string_list("components")
      .defaults(json::array({"x", "y", "z"}))
      .choices({"x", "y", "z"})
      .doc("displacement components prescribed; the others stay free (e.g. [\"z\"] for a frictionless support)")
      .to<&Selection::components>();
  d.string("name")
      .optional()
      .doc("label of this set in reactions.csv and summary.json; default: the group name, or the selector's shape")
      .to<&Selection::name>();
}

NodeSetBoundary::NodeSetBoundary(const Parameters& parameters, Vec3 final_displacement, Mat3 final_gradient)
    : parameters_(parameters),
      selector_(NodeSelector::from(parameters, "nodes")),
      final_displacement_(final_displacement),
      final_gradient_(final_gradient) {
  const auto [components, name] = parameters.read<Selection>();
  if (components.empty())
    throw InputError(parameters.pointer("components"), "give at least one of \"x\", \"y\", \"z\"");
  std::array<bool, 3> constrained{false, false, false};
  for (const auto& c : components) constrained[static_cast<std::size_t>(c[0] - 'x')] = true;
  set_.set_components(constrained);
  if (name) {
    set_.name = *name;
  } else if (selector_.kind == NodeSelector::Kind::group) {
    set_.name = selector_.group;
  } else {
    set_.name = fmt::format("{}{}", parameters.component(), parameters.pointer().substr(parameters.pointer().rfind('/') + 1));
  }
}

void NodeSetBoundary::setup(const Discretisation& model) {
  std::vector<Index> nodes = select_nodes(selector_, model.mesh(), model.cloud().surface, parameters_.pointer("nodes"));
  if (nodes.empty())
    throw InputError(parameters_.pointer("nodes"),
                     fmt::format("selects no node of the mesh ({}): check the coordinates (in m) and the tolerance",
                                 selector_.describe()));
  for (Index n : nodes) positions_.push_back(model.nodes()[n]);
  set_.assign_nodes(std::move(nodes), Vec3::Zero());
  log().info("boundary \"{}\": {} nodes ({})", set_.name, set_.size(), selector_.describe());
}

void NodeSetBoundary::update(const LoadState& load, const Discretisation&, std::span<const double>) {
  for (std::size_t k = 0; k < set_.values.size(); ++k)
    set_.values[k] = load.load_fraction * (final_displacement_ + final_gradient_ * positions_[k]);
}

}  // namespace mtled
