#include "plane_contact.hpp"

#include <fmt/format.h>

#include "mtled/discretisation.hpp"
#include "mtled/errors.hpp"

namespace mtled {

PlaneContact::PlaneContact(std::string name, const Plane& plane, bool stick, long release_steps,
                           const std::string& pointer)
    : plane_(plane), stick_(stick), release_steps_(release_steps) {
  set_.name = std::move(name);
  if (stick_) return;
  Index axis = 0;
  if (plane_.normal.cwiseAbs().maxCoeff(&axis) < 1.0 - 1e-12)
    throw InputError(pointer, fmt::format("a frictionless contact needs a plane normal to x, y or z; its normal is "
                                          "({:g}, {:g}, {:g}): use \"stick\" instead, or rotate the scene",
                                          plane_.normal.x(), plane_.normal.y(), plane_.normal.z()));
  set_.set_components({axis == 0, axis == 1, axis == 2});
}

std::size_t PlaneContact::setup(const Discretisation& model, const std::vector<Index>& candidates) {
  const double tolerance = 1e-6 * model.cloud().length_scale;  // the node selectors' default tolerance
  for (Index n : candidates)
    if ((model.nodes()[n] - plane_.point).dot(plane_.normal) > tolerance) candidates_.push_back(n);
  in_contact_.assign(static_cast<std::size_t>(model.node_count()), 0);
  return candidates_.size();
}

void PlaneContact::update(const LoadState& load, const Discretisation& model, std::span<const double> u) {
  const Vec3 point = plane_.point + load.load_fraction * plane_.displacement;
  release_pulled_nodes();
  for (std::size_t k = 0; k < set_.size(); ++k)
    set_.values[k] = on_plane(model, set_.nodes()[k], entries_[k].tangential, point);
  for (Index n : candidates_) {
    if (in_contact_[static_cast<std::size_t>(n)]) continue;
    const Vec3 displacement = model.interpolate_node(n, u);
    if ((model.nodes()[n] + displacement - point).dot(plane_.normal) >= 0.0) continue;
    const Vec3 tangential =
        stick_ ? Vec3(displacement - displacement.dot(plane_.normal) * plane_.normal) : Vec3::Zero();
    in_contact_[static_cast<std::size_t>(n)] = 1;
    entries_.push_back({tangential, 0});
    set_.add_node(n, on_plane(model, n, tangential, point));
  }
}

// The displacement that puts `node` on the plane through `point`, its tangential part `tangential`.
Vec3 PlaneContact::on_plane(const Discretisation& model, Index node, const Vec3& tangential, const Vec3& point) const {
  return tangential + (point - model.nodes()[node]).dot(plane_.normal) * plane_.normal;
}

void PlaneContact::release_pulled_nodes() {
  if (set_.reactions.size() != set_.size()) return;  // no step taken since the last change
  bool any = false;
  for (std::size_t k = 0; k < set_.size(); ++k) {
    Entry& entry = entries_[k];
    entry.tensile_steps = set_.reactions[k].dot(plane_.normal) < 0.0 ? entry.tensile_steps + 1 : 0;
    any = any || entry.tensile_steps >= release_steps_;
  }
  if (!any) return;  // the usual step: nothing to rebuild
  std::vector<char> keep(set_.size(), 1);
  std::vector<Entry> kept;
  for (std::size_t k = 0; k < set_.size(); ++k) {
    keep[k] = entries_[k].tensile_steps < release_steps_;
    if (keep[k])
      kept.push_back(entries_[k]);
    else
      in_contact_[static_cast<std::size_t>(set_.nodes()[k])] = 0;
  }
  entries_ = std::move(kept);
  set_.keep_entries(keep);
}

std::vector<Index> surface_node_list(const Discretisation& model) {
  std::vector<Index> nodes;
  for (Index n = 0; n < model.node_count(); ++n)
    if (model.cloud().surface[static_cast<std::size_t>(n)]) nodes.push_back(n);
  return nodes;
}

}  // namespace mtled
