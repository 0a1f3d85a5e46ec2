#pragma once
// The internal forces of a state u on the host: f_I = sum_ip w F S (grad N_I + correction) over the
// discretisation's rows, on its thread team, with the run-time state that takes (the padded displacement, one
// force buffer per thread, the slots each thread's share writes). A volumetric treatment, when the scene has one,
// replaces the evaluation by its own passes built from the two primitives below (deformation_gradients,
// scatter_stresses). The step engines evaluate through it (the CPU's every step; a device's when it checks or
// outputs), and so do the outputs that need the stress the forces used. Its calls are not re-entrant: they share
// the buffers (const only so that readers of a const kernel can evaluate).
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "mtled/discretisation.hpp"
#include "mtled/interfaces/volumetric_treatment.hpp"

namespace mtled {

class ForceKernel {
 public:
  // `volumetric` (null: each integration point's own F) is set up for this discretisation here.
  ForceKernel(const Discretisation& discretisation, std::shared_ptr<VolumetricTreatment> volumetric);
  ~ForceKernel();
  ForceKernel(const ForceKernel&) = delete;
  ForceKernel& operator=(const ForceKernel&) = delete;

  const Discretisation& discretisation() const { return discretisation_; }
  const VolumetricTreatment* volumetric_treatment() const { return volumetric_.get(); }

  // Internal nodal forces for nodal parameters u (3 per node), or the volumetric treatment's. Returns -1, or the
  // lowest-numbered integration point whose F is inadmissible (J <= 0 or not finite); f is then incomplete.
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
  // The strain energy of u (J), with the volumetric treatment.
  double strain_energy(std::span<const double> u) const;
  // The deformation gradient each point's stress comes from in internal_forces: the volumetric treatment's (F-bar's
  // F_bar), else the point's own. Returns -1, or the lowest-numbered inadmissible point.
  Index stress_deformation_gradients(std::span<const double> u, std::span<Mat3> F) const;

  // The two passes a volumetric treatment builds its forces from, each parallel on the team, over every point or the
  // points of some ranges (F and the stresses indexed by point; f's other contributions zero): F at the points
  // (returns -1 or the lowest-numbered inadmissible point), and f_I = sum_ip s_ip t_ip,I from per-point stresses s_ip
  // already multiplied by the point's weight.
  Index deformation_gradients(std::span<const double> u, std::span<Mat3> F) const;
  Index deformation_gradients(std::span<const double> u, std::span<Mat3> F, std::span<const PointRange> ranges) const;
  void scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f) const;
  void scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f,
                        std::span<const PointRange> ranges) const;

  // The fewest bytes one internal_forces() call must move through memory: the rows once (padding included; the
  // scatter re-reads them from the cache; stored test gradients too), each point's weight, mean correction (unless
  // the rows store test gradients) and material, the per-node displacements, corrections and forces once (each
  // thread's force buffer zeroed, filled and summed). Over the call's time, the kernel's achieved memory bandwidth.
  std::int64_t streamed_bytes_per_force_evaluation() const;

 private:
  const GradientRows& rows() const { return discretisation_.gradients(); }
  ThreadTeam& team() const { return discretisation_.team(); }
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

  const Discretisation& discretisation_;
  std::shared_ptr<VolumetricTreatment> volumetric_;
  mutable AlignedVector<double> padded_u_;
  mutable std::vector<AlignedVector<double>> thread_forces_;
  mutable std::vector<Index> thread_first_bad_;
  // thread_slots(): for each set of ranges asked, the slots of each thread
  mutable std::vector<std::pair<std::vector<PointRange>, std::vector<PointRange>>> thread_slots_;
};

}  // namespace mtled
