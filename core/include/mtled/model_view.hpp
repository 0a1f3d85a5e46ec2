#pragma once
// What drivers (boundary conditions, needles), monitors, writers and post-processing may see of the meshless
// model: the cloud (nodes, surface, spacing, supports), interpolation, and the integration points' geometry,
// materials and deformation gradients, all read-only. The kernel's own machinery (the thread team, the gradient
// rows the force kernel streams, the force buffers) stays behind it, in Model, which only the kernel, volumetric
// treatments and step engines see.
#include <span>
#include <vector>

#include "mtled/interfaces/material.hpp"
#include "mtled/mesh.hpp"
#include "mtled/point_search.hpp"
#include "mtled/support_rows.hpp"
#include "mtled/types.hpp"

namespace mtled {

class Model;

class ModelView {
 public:
  explicit ModelView(const Model& model);

  // ---- the cloud, in the reference configuration
  const TetMesh& mesh() const { return *mesh_; }  // the background tets, regions and named node sets
  Index node_count() const { return static_cast<Index>(nodes_->size()); }
  const std::vector<Vec3>& nodes() const { return *nodes_; }
  const std::vector<char>& surface() const { return *surface_; }         // 1 for nodes on the body's surface
  const std::vector<double>& node_spacing() const { return *spacing_; }  // mean edge length at each node (m)
  const std::vector<double>& support_radius() const { return *radius_; }  // each node's support radius (m)
  double length_scale() const;                                            // the bounding box's diagonal (m)
  const PointSearch& node_search() const { return *search_; }

  // ---- interpolation: u(X_J) = sum_I N_I(X_J) u_I for nodal parameters u (3 per node)
  void interpolate(std::span<const double> u, std::span<double> out) const;
  Vec3 interpolate_node(Index node, std::span<const double> u) const;
  const SupportRows& node_interpolation() const { return *interpolation_; }  // N_I(X_J), one row per node J
  // Shape functions at any point of the body; false if no support covers it or the fit fails.
  bool shape_functions_at(const Vec3& x, std::vector<Index>& nodes, std::vector<double>& values) const;

  // ---- integration points
  Index integration_point_count() const { return static_cast<Index>(ip_positions_->size()); }
  const std::vector<Vec3>& ip_positions() const { return *ip_positions_; }
  const std::vector<double>& ip_weights() const { return *ip_weights_; }  // m^3
  const std::vector<Index>& ip_tets() const { return *ip_tets_; }          // the background tet each lies in
  const Material& ip_material(Index ip) const;
  Mat3 deformation_gradient(Index ip, std::span<const double> u) const;
  // At every point, the deformation gradient its stress comes from in the forces (a volumetric treatment's F_bar,
  // else its own F); empty when some point's F is inadmissible.
  std::vector<Mat3> stress_deformation_gradients(std::span<const double> u) const;
  // Appends the nodes of point ip's support: the u_I deformation_gradient(ip, u) reads.
  void append_point_support(Index ip, std::vector<Index>& nodes) const;
  // Appends the nodes of node J's interpolation support: the u_I interpolate_node(J, u) reads.
  void append_node_support(Index node, std::vector<Index>& nodes) const;

  // ---- mass and stiffness
  // Lumped mass per node (kg) for the unscaled densities.
  std::vector<double> lumped_mass() const;
  // Each node's explicit-dynamics stiffness m_I / dt_I^2 (N/m): the sum over the integration points it supports of
  // rho w / (n dt^2), with n the point's support size and dt its critical step. It does not depend on mass scaling
  // (a scaled point's rho w / dt^2 is unchanged).
  std::vector<double> explicit_node_stiffness() const;
  // The strain energy of state u (J), with the scene's volumetric treatment.
  double strain_energy(std::span<const double> u) const;

 private:
  const Model* model_;
  const TetMesh* mesh_;
  const std::vector<Vec3>* nodes_;
  const std::vector<char>* surface_;
  const std::vector<double>* spacing_;
  const std::vector<double>* radius_;
  const PointSearch* search_;
  const SupportRows* interpolation_;
  const std::vector<Vec3>* ip_positions_;
  const std::vector<double>* ip_weights_;
  const std::vector<Index>* ip_tets_;
};

}  // namespace mtled
