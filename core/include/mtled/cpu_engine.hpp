#pragma once
// The kernel's own StepEngine: the state in host memory, the work on the discretisation's thread team (the force
// kernel, and the per-node passes of the update and the step's sums). Scenes without a "backend" block run on it; the
// "cpu" backend plugin (plugins/backends/cpu.cpp) names it.
#include <memory>
#include <span>
#include <vector>

#include "mtled/interfaces/backend.hpp"
#include "mtled/scope_timer.hpp"

namespace mtled {

// The state an engine keeps in host memory, three values per node (mass: one per node): u_n, u_(n-1), the prediction
// u~ and its copy before the constraint projection, f_int(u_n) and f_int(u_(n-1)). An engine that does the per-node
// work on part of the nodes (the mpi backend: a rank's own) holds one too.
struct HostState {
  std::vector<double> u, u_previous, prediction, free, f, f_previous, mass;
  // Every vector but the mass, zero at 3 x `nodes` values.
  void size_for(Index nodes);
  void set_state(std::span<const double> u_now, std::span<const double> u_before);
  void set_prediction(std::span<const double> u_predicted);

  // The step's per-node work on nodes [begin, end) (explicit_update.hpp), for an engine to share out as it will.
  // The prediction and its unconstrained copy; returns the first non-finite unknown, or -1.
  std::int64_t predict(const UpdateCoefficients& update, const double* f_ext, std::size_t begin, std::size_t end);
  // Node i's part of the step's sums, the prediction being u_(n+1).
  void add_step_sums(std::size_t i, double beta, StepSums& sums, double& fastest_energy) const;
  // u_(n+1) becomes u_n: the vectors swapped, nothing copied.
  void advance();
};

// The force kernel's evaluations (the step's and the monitors' extra ones), counted and timed: describe() says the mean
// time per evaluation and the memory bandwidth it reached (the bytes it must move,
// ForceKernel::streamed_bytes_per_force_evaluation, over that time): how close the run came to the machine.
class ForceEvaluationClock {
 public:
  template <class Compute>
  auto timed(Compute&& compute) {
    const ScopeTimer timer(seconds_);
    ++evaluations_;
    return compute();
  }
  // "force_evaluations", and "force_kernel_s", "force_kernel_bytes", "force_kernel_GB_per_s" once there was one.
  void describe(const ForceKernel& kernel, json& out) const;

 private:
  long evaluations_ = 0;
  double seconds_ = 0.0;
};

class CpuEngine : public StepEngine {
 public:
  void setup(const ForceKernel& kernel) override;
  json describe() const override;

  void set_mass(std::span<const double> mass) override;
  void set_state(std::span<const double> u, std::span<const double> u_previous) override;
  std::span<const double> displacement() override { return state_.u; }
  std::span<const double> previous_displacement() override { return state_.u_previous; }

  Index evaluate_forces(IncrementSums* sums) override;
  std::int64_t predict(const UpdateCoefficients& update, std::span<const double> f_ext) override;
  void set_prediction(std::span<const double> u) override;
  void prediction(std::span<double> out) override;
  void constrained_values(const ConstraintBlock& block, std::vector<double>& out) override;
  void add_correction(const ConstraintBlock& block, const std::vector<double>& y) override;
  StepSums commit(bool whole_displacement, double beta) override;
  Index internal_forces(std::span<const double> u, std::span<double> f) override;

 private:
  // One share's part of the step's sums, and the energy of its fastest node.
  struct Partial {
    StepSums sums;
    double fastest_energy = 0.0;
  };
  int parts_for(Index nodes) const;
  // body(begin, end, part) over `parts` contiguous shares of the nodes, on the team when there are several.
  template <class Body>
  void for_each_node_share(Body&& body, int parts);

  const ForceKernel* kernel_ = nullptr;
  HostState state_;
  ForceEvaluationClock clock_;
  // Seconds in the step's per-node work and the constraint products (describe(): "update_s", what a partition divides
  // besides the forces; the partition study reads it), summed by a ScopeTimer in each of those calls.
  double update_s_ = 0.0;
  std::vector<std::int64_t> first_bad_;  // per share: the first non-finite unknown of the prediction
  std::vector<Partial> partial_;
};

std::unique_ptr<StepEngine> make_cpu_engine();

}  // namespace mtled
