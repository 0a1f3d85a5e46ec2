#pragma once
// Where the time step's work on the state runs. A StepEngine holds the state of the explicit update (u_n, u_(n-1),
// the step's prediction, the internal forces) and does the per-node and per-point work of a step: the internal
// forces, the damped central-difference update, the constraint projection's two products and the step's
// reductions. The kernel's own engine runs it on the CPU's thread team (core/src/cpu_engine.cpp); a backend plugin
// ("backend": {"type": "cuda"}) runs it on a device, where the state and everything precomputed stay, so that only
// a few values per step cross to the host: the constraint products' rows, the step's sums and the displacements the
// drivers read. The MechanicalSystem drives it (mechanical_system.cpp); nothing else calls it but the monitors' extra
// force evaluations.
#include <cstdint>
#include <span>
#include <vector>

#include "mtled/interfaces/integrator.hpp"
#include "mtled/json.hpp"

namespace mtled {

class ForceKernel;
struct ConstraintBlock;
struct TetMesh;

class StepEngine {
 public:
  static constexpr Category category = Category::backend;
  virtual ~StepEngine();

  // Asked before the discretisation is built: per tet, the group its integration points go in
  // (Discretisation::Options::cell_groups),
  // for an engine that splits the points between processes; empty (the default): one group.
  virtual std::vector<int> cell_groups(const TetMesh& mesh);
  // Takes the host's force kernel and through it the discretisation's precomputed data (rows, weights, materials,
  // threads). Throws InputError when it cannot run this scene, saying what it lacks and how to run on the CPU instead.
  virtual void setup(const ForceKernel& kernel) = 0;
  // summary.json's "backend": at least "type", and where it ran.
  virtual json describe() const = 0;

  virtual void set_mass(std::span<const double> mass) = 0;  // per node (kg)
  // The state u_n and u_(n-1), 3 per node, from the host.
  virtual void set_state(std::span<const double> u, std::span<const double> u_previous) = 0;
  // u_n and u_(n-1) on the host (a device copies them back; valid until the next call that changes the state).
  virtual std::span<const double> displacement() = 0;
  virtual std::span<const double> previous_displacement() = 0;
  // u_n right at `nodes` at least (the drivers' reads), and at the nodes this process's forces read. An engine that
  // spreads the nodes over processes, or keeps them on a device, brings just those; every process calls it with the
  // same nodes. The default: displacement().
  virtual std::span<const double> displacement_at(std::span<const Index> nodes);
  // Whether displacement_at brings only the nodes asked for (the nodes are spread over processes, or on a device);
  // where it does not (the default), the read plan (read_plan.hpp) does not ask the drivers which nodes they read.
  virtual bool spreads_nodes() const;

  // f_n = f_int(u_n), kept for predict(); with `sums`, IncrementSums too. Returns -1, or the lowest-numbered
  // integration point whose F is inadmissible.
  virtual Index evaluate_forces(IncrementSums* sums) = 0;
  // u~ = u_n + beta (u_n - u_(n-1)) + alpha M^-1 (f_ext - f_n - gamma (f_n - f_(n-1))) (UpdateCoefficients), f_ext
  // empty for none. Returns -1, or the first unknown of u~ that is not finite.
  virtual std::int64_t predict(const UpdateCoefficients& update, std::span<const double> f_ext) = 0;
  // u~ from the host instead (a step an integrator computed itself), and back to the host.
  virtual void set_prediction(std::span<const double> u) = 0;
  virtual void prediction(std::span<double> out) = 0;
  // The constraint projection's two products on u~ (constraints.hpp): out = Phi u~ for one block, and
  // u~ += M^-1 Phi^T y.
  virtual void constrained_values(const ConstraintBlock& block, std::vector<double>& out) = 0;
  virtual void add_correction(const ConstraintBlock& block, const std::vector<double>& y) = 0;
  // u~ becomes u_(n+1) (u_(n-1) <- u_n <- u~); returns the step's sums. `whole_displacement`: a monitor on some
  // process reads u_(n+1) at every node (an engine that spreads the nodes over processes gathers it then, and
  // otherwise brings each process only what its forces read; displacement() gathers it on demand, every process
  // calling it alike). `beta`: the update's factor on u_n - u_(n-1), for StepSums::largest_residual_step (1 where
  // the step came from set_prediction).
  virtual StepSums commit(bool whole_displacement, double beta) = 0;

  // f = f_int(u) for host vectors, the state untouched (the monitors' extra evaluations, and integrators outside the
  // central-difference family). Returns -1 or the lowest-numbered inadmissible integration point.
  virtual Index internal_forces(std::span<const double> u, std::span<double> f) = 0;
};

}  // namespace mtled
