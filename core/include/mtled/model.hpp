#pragma once
// The meshless discretisation of MTLED: field nodes at the mesh vertices, integration points in the
// background tets, MLS-type shape functions on node-centred supports (R_I = d_c x mean edge length at I),
// all in the reference configuration (Total Lagrangian: computed once). Shape-function gradients and
// support lists are stored contiguously, one row per integration point, in blocks the vectorised force kernel
// streams (GradientRows).
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "mtled/gradient_rows.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/interfaces/volumetric_treatment.hpp"
#include "mtled/mesh.hpp"
#include "mtled/model_view.hpp"
#include "mtled/point_search.hpp"
#include "mtled/support_rows.hpp"
#include "mtled/thread_team.hpp"

namespace mtled {

struct SupportStatistics {
  Index min = 0, max = 0;
  double mean = 0.0;
  double min_reciprocal_condition = 0.0;
};

class Model {
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
    // How the volume change enters the stress (null: each integration point's own F). Set up at the end of
    // the model's construction, then called for every force and energy evaluation.
    std::shared_ptr<VolumetricTreatment> volumetric;
    // Threads of the force evaluation; 0: OpenMP's count (omp_get_max_threads(), set by --threads).
    int threads = 0;
    // The precision of the kernel's rows (RowPrecision). Double here, for code that builds models itself and checks
    // round-off; scenes default to single (/discretisation/precision).
    RowPrecision precision = RowPrecision::double_precision;
    // Per tet, the group its integration points belong to (empty: one group). The points are numbered group by
    // group (tet order within a group), so that each group's points are one contiguous range: a distributed step
    // engine gives each process a run of consecutive groups (StepEngine::cell_groups).
    std::vector<int> cell_groups;
  };

  // `region_materials[r]` fills mesh region r.
  Model(TetMesh mesh, std::shared_ptr<const ShapeFunctions> shape_functions,
        std::vector<std::shared_ptr<const Material>> region_materials, Options options);
  ~Model();

  // The read-only view drivers, monitors, writers and post-processing get.
  const ModelView& view() const { return *view_; }

  // Geometry
  const TetMesh& mesh() const { return mesh_; }
  Index node_count() const { return mesh_.node_count(); }
  const std::vector<Vec3>& nodes() const { return mesh_.points; }
  const std::vector<char>& surface() const { return surface_; }
  const std::vector<double>& node_spacing() const { return spacing_; }  // mean edge length per node
  const std::vector<double>& support_radius() const { return radius_; }
  double length_scale() const { return length_scale_; }  // bounding-box diagonal
  const PointSearch& node_search() const { return *node_search_; }

  // Integration points
  Index integration_point_count() const { return static_cast<Index>(ip_weight_.size()); }
  // The one range of every integration point, for the calls that take ranges.
  std::span<const PointRange> every_point() const { return {&every_point_, 1}; }
  const std::vector<Vec3>& ip_positions() const { return ip_position_; }
  const std::vector<double>& ip_weights() const { return ip_weight_; }
  const std::vector<Index>& ip_tets() const { return ip_tet_; }
  const Material& ip_material(Index ip) const { return *materials_[ip_material_[ip]]; }
  ThreadTeam& team() const { return *team_; }
  const GradientRows& ip_supports() const { return ip_rows_; }      // gradients
  const SupportRows& node_interpolation() const { return node_rows_; }  // values at the nodes
  SupportStatistics ip_support_statistics() const { return ip_stats_; }

  // Lumped mass per node from per-integration-point density multipliers (empty: none). Each integration
  // point gives rho w / n to each of its n support nodes.
  std::vector<double> lumped_mass(std::span<const double> density_scale = {}) const;
  // Critical time step of each integration point for the unscaled density (Joldes et al. 2012):
  // dt = 2 / (c sqrt(n sum_I |grad N_I|^2)), c = sqrt((lambda + 2 mu) / rho).
  const std::vector<double>& ip_critical_time_steps() const { return ip_dt_; }
  // How much stiffer each integration point's material is at the displacement u than at rest: the largest eigenvalue
  // of its tangent dP/dF at u over that at F = I, at least 1 (a softer point, or one whose F the law refuses, gets 1).
  // Its critical step at u is about ip_critical_time_steps() / sqrt(this). At each point's own F (a volumetric
  // treatment's average is left out: this only sizes masses). Parallel on the model's team.
  std::vector<double> ip_stiffening(std::span<const double> u) const;

  // The correction of node I's test-function gradient at integration point ip, xi_I - mean over ip's support of
  // xi_J (zero when consistent integration is off).
  Vec3 gradient_correction(Index ip, Index node) const {
    const double* xi = xi_.data() + 4 * static_cast<std::size_t>(ip_rows_.slot(node));
    const double* mean = xi_mean_.data() + 3 * static_cast<std::size_t>(ip);
    return {xi[0] - mean[0], xi[1] - mean[1], xi[2] - mean[2]};
  }
  // The test-function gradient of entry k of integration point ip: the stored gradient plus its correction, what the
  // internal forces multiply the stress by (f_I = sum_p w_p P_p t_pI).
  Vec3 test_gradient(Index ip, int k) const {
    return ip_rows_.gradient(ip, k) + gradient_correction(ip, ip_rows_.node(ip, k));
  }

  // The integration points of cell group g (Options::cell_groups): [first, second).
  std::pair<Index, Index> group_points(int group) const {
    return {group_offsets_[static_cast<std::size_t>(group)], group_offsets_[static_cast<std::size_t>(group) + 1]};
  }
  int group_count() const { return static_cast<int>(group_offsets_.size()) - 1; }

  // Internal nodal forces f_I = sum_ip w F S (grad N_I + gradient_correction(ip, I)) for nodal parameters u (3
  // per node), or the volumetric treatment's. Returns -1, or the lowest-numbered integration point whose F is
  // inadmissible (J <= 0 or not finite); f is then incomplete. Parallel over integration points (the model's
  // ThreadTeam); not re-entrant.
  Index internal_forces(std::span<const double> u, std::span<double> f) const;
  // The contributions of the integration points of some ranges [first, second) only (every node of f is written;
  // the nodes no point of the ranges supports get zero); the threads share the ranges' points in order. `progress`,
  // when given, is called on the calling thread every few thousand of its points (an engine that exchanges data
  // between processes meanwhile lets its messages move). With a volumetric treatment, its own sum over the ranges
  // (VolumetricTreatment::sums_over_ranges; std::logic_error for one that does not).
  Index internal_forces(std::span<const double> u, std::span<double> f, std::span<const PointRange> ranges,
                        const std::function<void()>& progress = {}) const;
  // The integration points whose deformation gradients internal_forces(u, f, ranges) computes: the ranges, or with
  // a volumetric treatment those its averages use. Their supports are the nodes of u the evaluation reads.
  std::vector<PointRange> points_read(std::span<const PointRange> ranges) const;
  double strain_energy(std::span<const double> u) const;
  // The fewest bytes one internal_forces() call must move through memory: the rows once (padding included; the
  // scatter re-reads them from the cache; stored test gradients too), each point's weight, mean correction (unless
  // the rows store test gradients) and material, the per-node displacements, corrections and forces once (each
  // thread's force buffer zeroed, filled and summed). Over the call's time, the kernel's achieved memory bandwidth.
  std::int64_t streamed_bytes_per_force_evaluation() const;
  const VolumetricTreatment* volumetric_treatment() const { return volumetric_.get(); }

  // The two passes a volumetric treatment builds its forces from, each parallel on the model's team:
  // F at every integration point (NaN-free; returns -1 or the lowest-numbered inadmissible point), and
  // f_I = sum_ip s_ip (grad N_I + gradient_correction(ip, I)) from per-point stresses s_ip already multiplied
  // by the point's weight.
  // Both over the points of some ranges only (F and the stresses indexed by point; f's other contributions zero).
  Index deformation_gradients(std::span<const double> u, std::span<Mat3> F) const;
  Index deformation_gradients(std::span<const double> u, std::span<Mat3> F, std::span<const PointRange> ranges) const;
  void scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f) const;
  void scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f,
                        std::span<const PointRange> ranges) const;
  Mat3 deformation_gradient(Index ip, std::span<const double> u) const;
  // The deformation gradient each point's stress comes from in internal_forces: the volumetric treatment's (F-bar's
  // F_bar), else the point's own. Returns -1, or the lowest-numbered inadmissible point. Not re-entrant.
  Index stress_deformation_gradients(std::span<const double> u, std::span<Mat3> F) const;
  // Interpolated displacement at every node: u(X_J) = sum_I N_I(X_J) u_I.
  void interpolate(std::span<const double> u, std::span<double> out) const;
  Vec3 interpolate_node(Index node, std::span<const double> u) const;

  // Shape functions at any point of the body (nodes whose supports cover it). False if none do or the fit
  // fails.
  bool shape_functions_at(const Vec3& x, std::vector<Index>& nodes, std::vector<double>& values) const;

 private:
  void build_integration_points(int points_per_tet, const std::vector<int>& cell_groups);
  void build_supports(RowPrecision precision);
  void build_time_steps();
  void build_integration_correction();
  std::vector<Vec3> solve_integration_correction(std::vector<Vec3> residual) const;
  // Team tasks over thread `thread`'s share of the nodes: u into the padded per-node layout the kernel reads (4
  // per node, then the padding node's zeros); the per-thread force buffers summed into f.
  void pad_displacement(std::span<const double> u, int thread) const;
  Index accumulate_forces(Index begin, Index end, double* f4, const std::function<void()>* progress = nullptr) const;
  // The slots (begin, end) of the kernel's per-node arrays that each thread's share of `ranges` writes forces into:
  // only those of its buffer are zeroed and summed. Slots follow the rows' first use, so a contiguous share of the
  // points writes into a narrow band of them. Kept per set of ranges asked (the whole cloud; an MPI rank's boundary
  // and interior points, which it asks for in turn at every evaluation).
  std::span<const PointRange> thread_slots(std::span<const PointRange> ranges) const;
  void clear_thread_forces(int thread, std::span<const PointRange> slots) const;
  void reduce_thread_forces(std::span<double> f, int thread, std::span<const PointRange> slots) const;
  // Support lists of arbitrary points (at least the shape functions' minimum); throws InputError naming `what`.
  std::vector<std::vector<Index>> find_supports(const std::vector<Vec3>& points, const char* what) const;
  // Shape functions at the points on those supports: store(r, k, value, gradient) for each entry, gradients only
  // when asked for; returns the smallest reciprocal condition number of the fits.
  template <class Store>
  double evaluate_rows(const std::vector<Vec3>& points, const std::vector<std::vector<Index>>& supports,
                       bool gradients, const char* what, Store store) const;

  TetMesh mesh_;
  std::shared_ptr<const ShapeFunctions> shape_functions_;
  std::vector<std::shared_ptr<const Material>> materials_;  // per region
  std::vector<char> surface_;
  std::vector<double> spacing_;
  std::vector<double> radius_;
  double max_radius_ = 0.0;
  double length_scale_ = 0.0;
  std::unique_ptr<PointSearch> node_search_;

  std::vector<Index> group_offsets_;  // first integration point of each cell group, then the point count
  std::vector<Vec3> ip_position_;
  std::vector<double> ip_weight_;
  std::vector<Index> ip_tet_;
  std::vector<std::uint16_t> ip_material_;
  GradientRows ip_rows_;
  SupportRows node_rows_;
  SupportStatistics ip_stats_;
  std::vector<double> ip_dt_;
  // The force kernel's per-node arrays, 4 doubles per slot (x, y, z, 0; GradientRows::slot) and one padding slot of
  // zeros: the gradient correction, the displacement being evaluated, and one force accumulator per thread.
  AlignedVector<double> xi_;
  std::vector<double> xi_mean_;  // per integration point: the mean of xi_I over its support (3 doubles)
  mutable AlignedVector<double> padded_u_;
  mutable std::vector<AlignedVector<double>> thread_forces_;
  mutable std::vector<Index> thread_first_bad_;
  // thread_slots(): for each set of ranges asked, the slots of each thread
  mutable std::vector<std::pair<std::vector<PointRange>, std::vector<PointRange>>> thread_slots_;
  PointRange every_point_{0, 0};
  std::unique_ptr<ThreadTeam> team_;  // the time step's threads (setup loops use OpenMP)

  std::shared_ptr<VolumetricTreatment> volumetric_;
  std::unique_ptr<ModelView> view_;
};

}  // namespace mtled
