#include "node_set_boundary.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>

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
  d.string("platen")
      .defaults("none")
      .choices({"none", "frictionless", "stick"})
      .doc(
          "the nodes are a flat face bonded to a rigid platen that moves with them: the rest of the body's surface may "
          "not pass through the platen's plane, nodes that reach it slide on it (frictionless; a face normal to x, y "
          "or z) or stay where they touched (stick); their reactions are the set \"<name>_contact\". none: the "
          "platen is not modelled beyond the face")
      .to<&Selection::platen>();
}

NodeSetBoundary::NodeSetBoundary(const Parameters& parameters, Vec3 final_displacement, Mat3 final_gradient)
    : parameters_(parameters),
      selector_(NodeSelector::from(parameters, "nodes")),
      final_displacement_(final_displacement),
      final_gradient_(final_gradient) {
  const auto [components, name, platen] = parameters.read<Selection>();
  platen_ = platen;
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
  if (platen_ != "none") set_up_platen(model, nodes);
  set_.assign_nodes(std::move(nodes), Vec3::Zero());
  log().info("boundary \"{}\": {} nodes ({})", set_.name, set_.size(), selector_.describe());
}

// The platen's plane is the face's (fitted through its nodes: the normal of least spread), its normal pointing into
// the body; it moves as the face does, so the face must move rigidly, without turning.
void NodeSetBoundary::set_up_platen(const Discretisation& model, const std::vector<Index>& face) {
  const std::string pointer = parameters_.pointer("platen");
  if (!final_gradient_.isZero())
    throw InputError(pointer,
                     "a platen moves rigidly, and this face's displacement has a gradient: leave \"gradient\" "
                     "out, or set \"platen\" to \"none\"");
  Vec3 centre = Vec3::Zero(), body = Vec3::Zero();
  for (Index n : face) centre += model.nodes()[n];
  centre /= static_cast<double>(face.size());
  for (Index n = 0; n < model.node_count(); ++n) body += model.nodes()[n];
  body /= static_cast<double>(model.node_count());
  Mat3 spread = Mat3::Zero();
  for (Index n : face) spread += (model.nodes()[n] - centre) * (model.nodes()[n] - centre).transpose();
  Vec3 normal = Eigen::SelfAdjointEigenSolver<Mat3>(spread).eigenvectors().col(0);
  if ((body - centre).dot(normal) < 0.0) normal = -normal;
  double off_plane = 0.0, size = 0.0;
  for (Index n : face) {
    off_plane = std::max(off_plane, std::abs((model.nodes()[n] - centre).dot(normal)));
    size = std::max(size, (model.nodes()[n] - centre).norm());
  }
  if (face.size() < 3 || off_plane > 1e-6 * size)
    throw InputError(pointer, fmt::format("a platen needs a flat face, and these {} nodes lie up to {:.3g} m off one "
                                          "plane: select the face's nodes only, or set \"platen\" to \"none\"",
                                          face.size(), off_plane));
  // A face normal to x, y or z: its normal exactly so, so that the contact holds one component.
  Index axis = 0;
  if (normal.cwiseAbs().maxCoeff(&axis) > 1.0 - 1e-9) normal = Vec3::Unit(axis) * (normal[axis] > 0.0 ? 1.0 : -1.0);
  contact_.emplace(set_.name + "_contact", PlaneContact::Plane{centre, normal, final_displacement_}, platen_ == "stick",
                   kPlatenReleaseSteps, pointer);
  const std::size_t candidates = contact_->setup(model, surface_node_list(model));
  log().info("boundary \"{}\": a platen, {} surface nodes may touch its plane ({})", set_.name, candidates, platen_);
}

std::vector<NodalConstraints*> NodeSetBoundary::constraints() {
  if (contact_) return {&set_, &contact_->constraints()};
  return {&set_};
}

void NodeSetBoundary::update(const LoadState& load, const Discretisation& model, std::span<const double> u) {
  for (std::size_t k = 0; k < set_.values.size(); ++k)
    set_.values[k] = load.load_fraction * (final_displacement_ + final_gradient_ * positions_[k]);
  if (contact_) contact_->update(load, model, u);
}

}  // namespace mtled
