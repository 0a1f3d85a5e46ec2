#pragma once
// The kernel's own StepEngine: the state in host memory, the work on the discretisation's thread team (the force
// kernel, and the per-node passes of the update and the step's sums). Scenes without a "backend" block run on it; the
// "cpu" backend plugin (plugins/backends/cpu.cpp) names it.
#include <memory>
#include <vector>

#include "mtled/interfaces/backend.hpp"
#include "mtled/scope_timer.hpp"

namespace mtled {

class CpuEngine : public StepEngine {
 public:
  void setup(const ForceKernel& kernel) override;
  // With the force kernel's mean time per evaluation and the memory bandwidth it reached (the bytes it must move,
  // ForceKernel::streamed_bytes_per_force_evaluation, over that time): how close the run came to the machine.
  json describe() const override;

  void set_mass(std::span<const double> mass) override;
  void set_state(std::span<const double> u, std::span<const double> u_previous) override;
  std::span<const double> displacement() override { return u_; }
  std::span<const double> previous_displacement() override { return u_previous_; }

  Index evaluate_forces(IncrementSums* sums) override;
  std::int64_t predict(const UpdateCoefficients& update, std::span<const double> f_ext) override;
  void set_prediction(std::span<const double> u) override;
  void prediction(std::span<double> out) override;
  void constrained_values(const ConstraintBlock& block, std::vector<double>& out) override;
  void add_correction(const ConstraintBlock& block, const std::vector<double>& y) override;
  StepSums commit(bool whole_displacement, double beta) override;
  Index internal_forces(std::span<const double> u, std::span<double> f) override;

 protected:
  // f = f_int(u) over every node, for both calls above: the host's force kernel here; an engine that shares the
  // integration points between processes computes its own and completes f with the others' contributions.
  virtual Index forces(std::span<const double> u, std::span<double> f);
  // `compute` (a force evaluation), counted and timed as the force kernel's work for describe().
  template <class Compute>
  auto timed(Compute&& compute) {
    const ScopeTimer timer(kernel_s_);
    ++evaluations_;
    return compute();
  }
  const ForceKernel& kernel() const { return *kernel_; }

  // The state, for an engine that does the per-node work on part of the nodes itself (the mpi backend: a rank's own).
  std::vector<double> u_, u_previous_, prediction_, free_, f_, f_previous_, mass_;

  // Seconds in the step's per-node work and the constraint products (describe(): "update_s", what a partition divides
  // besides the forces; the partition study reads it), summed by a ScopeTimer in each of those calls.
  double update_s_ = 0.0;

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
  std::vector<std::int64_t> first_bad_;  // per share: the first non-finite unknown of the prediction
  std::vector<Partial> partial_;
  long evaluations_ = 0;  // of the forces (the step's and the monitors' extra ones), and their time
  double kernel_s_ = 0.0;
};

std::unique_ptr<StepEngine> make_cpu_engine();

}  // namespace mtled
