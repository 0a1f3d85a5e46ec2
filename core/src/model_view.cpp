#include "mtled/model_view.hpp"

#include "mtled/model.hpp"

namespace mtled {

ModelView::ModelView(const Model& model)
    : model_(&model),
      mesh_(&model.mesh()),
      nodes_(&model.nodes()),
      surface_(&model.surface()),
      spacing_(&model.node_spacing()),
      radius_(&model.support_radius()),
      search_(&model.node_search()),
      interpolation_(&model.node_interpolation()),
      ip_positions_(&model.ip_positions()),
      ip_weights_(&model.ip_weights()),
      ip_tets_(&model.ip_tets()) {}

double ModelView::length_scale() const { return model_->length_scale(); }

void ModelView::interpolate(std::span<const double> u, std::span<double> out) const { model_->interpolate(u, out); }

Vec3 ModelView::interpolate_node(Index node, std::span<const double> u) const { return model_->interpolate_node(node, u); }

bool ModelView::shape_functions_at(const Vec3& x, std::vector<Index>& nodes, std::vector<double>& values) const {
  return model_->shape_functions_at(x, nodes, values);
}

const Material& ModelView::ip_material(Index ip) const { return model_->ip_material(ip); }

std::vector<Mat3> ModelView::stress_deformation_gradients(std::span<const double> u) const {
  std::vector<Mat3> F(static_cast<std::size_t>(model_->integration_point_count()));
  if (model_->stress_deformation_gradients(u, F) >= 0) F.clear();
  return F;
}

Mat3 ModelView::deformation_gradient(Index ip, std::span<const double> u) const {
  return model_->deformation_gradient(ip, u);
}

void ModelView::append_point_support(Index ip, std::vector<Index>& nodes) const {
  const GradientRows& rows = model_->ip_supports();
  for (int k = 0; k < rows.size(ip); ++k) nodes.push_back(rows.node(ip, k));
}

void ModelView::append_node_support(Index node, std::vector<Index>& nodes) const {
  const SupportRows& rows = *interpolation_;
  nodes.insert(nodes.end(), rows.nodes.begin() + rows.offsets[node], rows.nodes.begin() + rows.offsets[node + 1]);
}

std::vector<double> ModelView::lumped_mass() const { return model_->lumped_mass(); }

std::vector<double> ModelView::explicit_node_stiffness() const {
  std::vector<double> stiffness(static_cast<std::size_t>(model_->node_count()), 0.0);
  const auto& rows = model_->ip_supports();
  const auto& dt = model_->ip_critical_time_steps();
  for (Index ip = 0; ip < model_->integration_point_count(); ++ip) {
    const double share = model_->ip_material(ip).density() * model_->ip_weights()[ip] /
                         (static_cast<double>(rows.size(ip)) * dt[ip] * dt[ip]);
    for (int k = 0; k < rows.size(ip); ++k) stiffness[rows.node(ip, k)] += share;
  }
  return stiffness;
}

double ModelView::strain_energy(std::span<const double> u) const { return model_->strain_energy(u); }

}  // namespace mtled
