#include "mtled/analysis/mls_transfer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "mtled/parameters.hpp"

namespace mtled {

namespace {

constexpr std::size_t kNeighbours = 10;

std::shared_ptr<ShapeFunctions> linear_mls(PluginCatalog& catalog) {
  const ComponentDeclaration& declaration = catalog.load(Category::shape_function, "mls", "MLS transfer");
  std::vector<Problem> problems;
  const Parameters parameters = validate_parameters(declaration, json::object(), "", problems);
  return catalog.create<ShapeFunctions>("mls", parameters);
}

}  // namespace

MlsTransfer::MlsTransfer(const std::vector<Vec3>& nodes, PluginCatalog& catalog)
    : nodes_(nodes), mls_(linear_mls(catalog)), search_(nodes), radius_(nodes.size()) {
  std::vector<Index> nearest;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    search_.nearest(nodes[i], kNeighbours + 1, nearest);  // the node itself comes first
    radius_[i] = 1.3 * (nodes[static_cast<std::size_t>(nearest.back())] - nodes[i]).norm();
  }
  max_radius_ = radius_.empty() ? 0.0 : *std::max_element(radius_.begin(), radius_.end());
}

Vec3 MlsTransfer::at(const Vec3& x, const std::vector<Vec3>& values) const {
  std::vector<Index> candidates, support;
  search_.within(x, max_radius_, candidates);
  for (Index i : candidates)
    if ((nodes_[static_cast<std::size_t>(i)] - x).norm() < radius_[static_cast<std::size_t>(i)]) support.push_back(i);
  if (static_cast<int>(support.size()) < mls_->minimum_support_size())
    search_.nearest(x, 2 * kNeighbours, support);  // outside the cloud (a coarser boundary): the nearest nodes
  std::vector<Vec3> coordinates;
  std::vector<double> radii, shape(support.size());
  for (Index i : support) {
    coordinates.push_back(nodes_[static_cast<std::size_t>(i)]);
    radii.push_back(
        std::max(radius_[static_cast<std::size_t>(i)], 1.01 * (nodes_[static_cast<std::size_t>(i)] - x).norm()));
  }
  if (!mls_->evaluate(x, coordinates, radii, shape, {}).ok)
    throw std::runtime_error(
        fmt::format("cannot interpolate at ({:g}, {:g}, {:g}): degenerate neighbourhood", x[0], x[1], x[2]));
  Vec3 out = Vec3::Zero();
  for (std::size_t k = 0; k < support.size(); ++k) out += shape[k] * values[static_cast<std::size_t>(support[k])];
  return out;
}

}  // namespace mtled
