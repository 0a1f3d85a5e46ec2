#pragma once
// The meshless discretisation of MTLED, built once from the mesh and then read-only: field nodes at the mesh
// vertices, integration points in the background tets, MLS-type shape functions on node-centred supports
// (R_I = d_c x mean edge length at I), all in the reference configuration (Total Lagrangian). Shape-function
// gradients and support lists are stored contiguously, one row per integration point, in blocks the vectorised
// force kernel streams (GradientRows). Drivers, monitors, writers and post-processing read it through a const
// reference; the force evaluation's run-time state lives apart, in the ForceKernel (force_kernel.hpp). What depends
// on the mesh alone (MeshlessBasis) is shared by discretisations of one mesh with other materials.
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "mtled/gradient_rows.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/mesh.hpp"
#include "mtled/point_search.hpp"
#include "mtled/support_rows.hpp"
#include "mtled/thread_team.hpp"

namespace mtled {

// The field nodes (the mesh's vertices, TetMesh::points), in the reference configuration.
struct NodeCloud {
  std::vector<char> surface;            // 1 for nodes on the body's surface
  std::vector<double> spacing;          // mean edge length at each node (m)
  std::vector<double> support_radius;   // each node's support radius (m)
  double max_support_radius = 0.0;      // (m)
  double length_scale = 0.0;            // the bounding box's diagonal (m)
  std::unique_ptr<PointSearch> search;  // nearest-neighbour and radius queries over the nodes
};

struct SupportStatistics {
  Index min = 0, max = 0;
  double mean = 0.0;
  double min_reciprocal_condition = 0.0;
};

// The integration points, numbered cell group by cell group (Discretisation::Options::cell_groups), each group's
// cells along a Morton curve.
struct IntegrationPoints {
  std::vector<Vec3> positions;
  std::vector<double> weights;                // m^3
  std::vector<Index> tets;                    // the background tet each lies in
  std::vector<std::uint16_t> material_index;  // into the region materials (the tet's region)
  SupportStatistics support;
  std::vector<Index> group_offsets;  // first point of each cell group, then the point count
  PointRange all{0, 0};

  Index count() const { return static_cast<Index>(weights.size()); }
  // The one range of every point, for the calls that take ranges.
  std::span<const PointRange> every() const { return {&all, 1}; }
  // The points of cell group g: [first, second).
  std::pair<Index, Index> group(int g) const {
    return {group_offsets[static_cast<std::size_t>(g)], group_offsets[static_cast<std::size_t>(g) + 1]};
  }
  int group_count() const { return static_cast<int>(group_offsets.size()) - 1; }
};

// Consistent integration's correction of the test-function gradients (Discretisation::Options), laid out for the
// force kernel: xi_I at each node's GradientRows slot (4 doubles: x, y, z, 0; then the padding slot's zeros) and,
// per integration point, the mean of xi_J over its support (3 doubles). All zero when the correction is off.
struct IntegrationCorrection {
  AlignedVector<double> at_slots;
  std::vector<double> means;
};

// Everything a discretisation builds from the mesh, the shape functions and its Options, none of it from the
// materials: a fit's forward runs, which change materials or the needle, build it once and share it (MechanicalSystem's
// BasisCache). Immutable once built.
struct MeshlessBasis {
  TetMesh mesh;
  std::shared_ptr<const ShapeFunctions> shape_functions;
  NodeCloud cloud;
  IntegrationPoints points;
  GradientRows gradients;            // grad N_I at the integration points
  SupportRows interpolation;         // N_I(X_J), one row per node J
  IntegrationCorrection correction;  // consistent integration's (zero when off)
};

class Discretisation {
 public:
  struct Options {
    int integration_points_per_tet = 1;
    // Variationally consistent integration (Chen, Hillman, Rueter, IJNME 2013): the test-function gradients
    // at the integration points get a correction so that sum_ip w grad N_I equals the boundary integral of
    // N_I n exactly. The discrete equations then reproduce any homogeneous deformation (the patch test)
    // despite the inexact quadrature of rational shape functions; F still uses the uncorrected gradients, so
    // rigid motions stay stress-free. The correction of node I at point p is xi_I - mean over p's support of
    // xi_J: the corrections at each point sum to zero, so the internal forces sum to zero and the reactions
    // balance (a per-node constant xi_I alone left 0.4-1.9% of the needle force unbalanced).
    bool consistent_integration = true;
    // Threads of the run's parallel loops (the force kernel's and the interpolation's); 0: OpenMP's count
    // (omp_get_max_threads(), set by --threads).
    int threads = 0;
    // The precision of the kernel's rows (RowPrecision). Double here, for code that builds discretisations itself
    // and checks round-off; scenes default to single (/discretisation/precision).
    RowPrecision precision = RowPrecision::double_precision;
    // Per tet, the group its integration points belong to (empty: one group). The points are numbered group by
    // group (tet order within a group), so that each group's points are one contiguous range: a distributed step
    // engine gives each process a run of consecutive groups (StepEngine::cell_groups).
    std::vector<int> cell_groups;
  };

  // `region_materials[r]` fills mesh region r.
  Discretisation(TetMesh mesh, std::shared_ptr<const ShapeFunctions> shape_functions,
                 std::vector<std::shared_ptr<const Material>> region_materials, Options options);
  // A basis built before (the same mesh, shape functions and Options), with these materials and `threads` (0: as
  // Options::threads).
  Discretisation(std::shared_ptr<const MeshlessBasis> basis,
                 std::vector<std::shared_ptr<const Material>> region_materials, int threads);
  ~Discretisation();
  Discretisation(const Discretisation&) = delete;
  Discretisation& operator=(const Discretisation&) = delete;

  // ---- what was built (the interpolation rows N_I(X_J) and the integration correction: basis()->...)
  const std::shared_ptr<const MeshlessBasis>& basis() const { return basis_; }
  const TetMesh& mesh() const { return basis_->mesh; }  // the background tets, regions and named node sets
  Index node_count() const { return basis_->mesh.node_count(); }
  const std::vector<Vec3>& nodes() const { return basis_->mesh.points; }
  const NodeCloud& cloud() const { return basis_->cloud; }
  const IntegrationPoints& points() const { return basis_->points; }
  const Material& material(Index ip) const { return *materials_[basis_->points.material_index[ip]]; }
  const GradientRows& gradients() const { return basis_->gradients; }  // grad N_I at the integration points
  // Critical time step of each integration point for the unscaled density (Joldes, Wittek, Miller, IJNME 2012):
  // dt = 2 / (c sqrt(n sum_I |grad N_I|^2)), c = sqrt((lambda + 2 mu) / rho).
  const std::vector<double>& critical_time_steps() const { return critical_time_steps_; }
  // The run's threads: the force kernel's, and the interpolation's between steps.
  ThreadTeam& team() const { return *team_; }

  // ---- reading a state u (nodal parameters, 3 per node)
  // Interpolated displacement at every node: u(X_J) = sum_I N_I(X_J) u_I; at one node.
  void interpolate(std::span<const double> u, std::span<double> out) const;
  Vec3 interpolate_node(Index node, std::span<const double> u) const;
  // F = I + sum_I u_I (x) grad N_I at point ip (each point's own; the force kernel's may be averaged).
  Mat3 deformation_gradient(Index ip, std::span<const double> u) const;
  // Shape functions at any point of the body (and their reference gradients, when `gradients` is given); false if no
  // support covers it or the fit fails.
  bool shape_functions_at(const Vec3& x, std::vector<Index>& nodes, std::vector<double>& values,
                          std::vector<Vec3>* gradients = nullptr) const;
  // Lumped mass per node (kg) from per-integration-point density multipliers (empty: none). Each integration
  // point gives rho w / n to each of its n support nodes.
  std::vector<double> lumped_mass(std::span<const double> density_scale = {}) const;

 private:
  void build_time_steps();

  std::shared_ptr<const MeshlessBasis> basis_;
  std::vector<std::shared_ptr<const Material>> materials_;  // per region
  std::vector<double> critical_time_steps_;
  std::unique_ptr<ThreadTeam> team_;
};

// The test-function gradient of entry k of point ip: the gradient plus consistent integration's correction,
// xi_I - mean over ip's support of xi_J, what the internal forces multiply the stress by (f_I = sum_p w_p P_p t_pI).
Vec3 test_gradient(const Discretisation& discretisation, Index ip, int k);

// The displacement field of nodal parameters u at any point X of the reference body (between the nodes and the
// integration points): u(X) = sum_I N_I(X) u_I and F = I + sum_I u_I (x) grad N_I (Discretisation::deformation_gradient
// gives an integration point's own); nullopt if no support covers X.
struct FieldSample {
  Vec3 displacement;
  Mat3 deformation_gradient;
};
std::optional<FieldSample> field_at(const Discretisation& discretisation, const Vec3& X, std::span<const double> u);

// How much stiffer each integration point's material is at the displacement u than at rest: the largest eigenvalue
// of its tangent dP/dF at u over that at F = I, at least 1 (a softer point, or one whose F the law refuses, gets 1).
// Its critical step at u is about Discretisation::critical_time_steps / sqrt(this). At each point's own F (a
// volumetric treatment's average is left out: this only sizes masses). Parallel on the discretisation's team.
std::vector<double> stiffening(const Discretisation& discretisation, std::span<const double> u);

}  // namespace mtled
